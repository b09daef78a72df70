// The outcome of a direct run as a sentence predicate (run/direct_runs.hpp): a run that diverged
// reads "diverged at iteration 162", never "needs diverged at 162".
#include <gtest/gtest.h>

#include "physgrad/run/cases/direct_runs.hpp"

namespace physgrad::run {
namespace {

DirectResult direct_outcome(Termination end, int iterations, double loss, double initial) {
  DirectResult r;
  r.summary.termination = end;
  r.summary.iterations = iterations;
  r.summary.loss = loss;
  r.initial_loss = initial;
  return r;
}

TEST(DirectOutcome, EachEndReadsAfterTheRuleName) {
  EXPECT_EQ(outcome_phrase(direct_outcome(Termination::kConverged, 688, 1e-9, 1)),
            "needs 688 iterations");
  EXPECT_EQ(outcome_phrase(direct_outcome(Termination::kNumericalFailure, 161, NAN, 1)),
            "diverged at iteration 162");
  EXPECT_EQ(outcome_phrase(direct_outcome(Termination::kFailed, 4, 0.5, 1)),
            "failed at iteration 5");
  EXPECT_EQ(outcome_phrase(direct_outcome(Termination::kStationary, 9, 0.5, 1)),
            "stalled at iteration 9");
  EXPECT_EQ(outcome_phrase(direct_outcome(Termination::kMaxIterations, 1000, 0.5, 1)),
            "has not converged after 1000 iterations");
  const DirectResult rising = direct_outcome(Termination::kMaxIterations, 1000, 4, 2);
  EXPECT_EQ(outcome_phrase(rising), "is " + iterations_cell(rising));
  EXPECT_EQ(outcome_phrase(rising).rfind("is diverging (L ×", 0), 0u);
}

}  // namespace
}  // namespace physgrad::run
