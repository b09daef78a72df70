// The verdict of a learning comparison (run/learning_verdict.hpp): updates and seconds to reach a
// level (brackets between evaluations), the update advantage N and step-cost ratio M against
// Adam, and failed, diverged or never-switched runs never ranked.
#include <gtest/gtest.h>

#include <cmath>

#include "experiment_runs.hpp"
#include "physgrad/run/cases/learning_runs.hpp"
#include "physgrad/run/pages/learning_verdict.hpp"

namespace physgrad::run {
namespace {

const auto kTestLoss = [](const TrainingRecord& r) { return r.test_loss; };

// A run of rule `id` whose test loss at iteration k·every is `losses[k]`, each update taking
// `seconds_per_update`.
LearningResult run(const std::string& id, const std::vector<double>& losses, long long every,
                   double seconds_per_update,
                   TrainingTermination end = TrainingTermination::kTimeBudget) {
  LearningResult r;
  r.id = id;
  r.label = learning_run_label(id);
  for (std::size_t k = 0; k < losses.size(); ++k) {
    TrainingRecord record;
    record.iteration = static_cast<long long>(k) * every;
    record.train_seconds = static_cast<double>(record.iteration) * seconds_per_update;
    record.train_loss = record.test_loss = losses[k];
    r.summary.history.push_back(record);
  }
  r.summary.iterations = r.summary.history.back().iteration;
  r.summary.train_seconds = r.summary.history.back().train_seconds;
  r.summary.termination = end;
  return r;
}

TEST(LearningVerdict, UpdatesToReachALevelInterpolateLogLinearly) {
  const LearningResult r = run("adam", {1.0, 0.1, 0.01}, 10, 0.5);
  EXPECT_DOUBLE_EQ(updates_to_reach(r.summary, 1.0, kTestLoss), 0);
  EXPECT_NEAR(updates_to_reach(r.summary, std::sqrt(0.1), kTestLoss), 5, 1e-12);
  EXPECT_NEAR(updates_to_reach(r.summary, 0.01, kTestLoss), 20, 1e-12);
  EXPECT_NEAR(seconds_to_reach(r.summary, 0.01, kTestLoss), 10, 1e-12);
  EXPECT_TRUE(std::isnan(updates_to_reach(r.summary, 0.001, kTestLoss)));
}

// HIG comes down to Adam's final 0.1 between its evaluations at 0 and 10, Adam between 6666 and
// 9999, at 5000× the cost a step: HIG ends lower and needs at least 670× fewer updates; in wall
// time the brackets (0 to 5 s, 0.67 to 1 s) do not tell which gets there sooner.
TEST(LearningVerdict, StatesTheUpdateAdvantageAndTheStepCostAgainstAdam) {
  const LearningResult adam = run("adam", {1.0, 0.5, 0.2, 0.1}, 3333, 1e-4);
  const LearningResult hig = run("hig", {1.0, 0.1, 0.05, 0.02}, 10, 0.5);
  const std::string sentence =
      verdict_sentence({{{&adam}, {&hig}}, kTestLoss, "final test loss"});
  EXPECT_NE(sentence.find("HIG's final test loss is 5× below Adam's (0.02 vs 0.1, one seed)"),
            std::string::npos)
      << sentence;
  EXPECT_NE(sentence.find("to reach 0.1 HIG needs between 0 and 10 updates, Adam between 6666 "
                          "and 9999 (at least 670× fewer)"),
            std::string::npos)
      << sentence;
  EXPECT_NE(sentence.find("its update costs 5000× Adam's"), std::string::npos) << sentence;
  EXPECT_NE(sentence.find("in wall time (measured at the same evaluations) the brackets do not "
                          "tell which gets there sooner (between 0 and 5 vs between 0.667 and 1 s)"),
            std::string::npos)
      << sentence;
}

// A failed or diverged run counts in no median and is never ranked; a twin that never switched is
// Adam's run, named as such; values within 10 % are about equal.
TEST(LearningVerdict, FailedDivergedAndUnswitchedRunsAreNeverRanked) {
  const LearningResult adam = run("adam", {1.0, 0.5}, 10, 1e-3);
  const LearningResult gn =
      run("gn", {1.0, 1e-9}, 10, 0.1, TrainingTermination::kNumericalFailure);
  const LearningResult hig = run("hig", {1.0, 2.0}, 10, 0.1, TrainingTermination::kDiverged);
  LearningResult twin = run("adam-hig", {1.0, 0.48}, 10, 1e-3);
  twin.params = {{"switched", false}};
  const std::string sentence =
      verdict_sentence({{{&adam}, {&gn}, {&hig}, {&twin}}, kTestLoss, "final test loss"});
  EXPECT_EQ(sentence.find("Gauss-Newton's final test loss"), std::string::npos) << sentence;
  EXPECT_NE(sentence.find("Adam's final test loss is 0.5"), std::string::npos) << sentence;
  EXPECT_NE(sentence.find("Gauss-Newton: 1 of 1 runs failed or diverged and are not ranked"),
            std::string::npos)
      << sentence;
  EXPECT_NE(sentence.find("HIG: 1 of 1 runs failed or diverged"), std::string::npos) << sentence;
  EXPECT_NE(sentence.find("Adam→HIG never switched from Adam"), std::string::npos) << sentence;
  EXPECT_FALSE(credited(gn));
  EXPECT_FALSE(credited(twin));
  EXPECT_TRUE(credited(adam));

  const LearningResult close = run("sgd", {1.0, 0.52}, 10, 1e-3);
  const std::string equal = verdict_sentence({{{&adam}, {&close}}, kTestLoss, "final test loss"});
  EXPECT_NE(equal.find("Adam's final test loss is about equal to SGD's (0.5 vs 0.52, one seed)"),
            std::string::npos)
      << equal;
  // Both come down to 0.52 between their evaluations at 0 and 10: neither is told sooner.
  EXPECT_NE(equal.find("the brackets do not tell which needs fewer"), std::string::npos)
      << equal;
  EXPECT_NE(equal.find("the brackets do not tell which gets there sooner (between 0 and 0.01 "
                       "vs between 0 and 0.01 s)"),
            std::string::npos)
      << equal;
}

// Two seeds each: Adam ends at 0.1 and 0.3 (median 0.2, which its second seed never reached),
// HIG at 0.01 and 0.03. The level compared is the upper median final (0.3), which both of Adam's
// seeds reached, so no count reads "nan" for an even number of seeds.
TEST(LearningVerdict, EvenSeedCountsGiveNumbersNotNan) {
  const LearningResult adam1 = run("adam", {1.0, 0.5, 0.1}, 100, 1e-3);
  const LearningResult adam2 = run("adam", {1.0, 0.6, 0.3}, 100, 1e-3);
  const LearningResult hig1 = run("hig", {1.0, 0.1, 0.01}, 10, 0.1);
  const LearningResult hig2 = run("hig", {1.0, 0.3, 0.03}, 10, 0.1);
  const std::string sentence = verdict_sentence(
      {{{&adam1, &adam2}, {&hig1, &hig2}}, kTestLoss, "final test loss"});
  EXPECT_EQ(sentence.find("nan"), std::string::npos) << sentence;
  // Adam's seeds reach 0.3 between their evaluations at 100 and 200.
  EXPECT_NE(sentence.find("to reach 0.3 HIG needs"), std::string::npos) << sentence;
  EXPECT_NE(sentence.find(", Adam between 100 and 200 ("), std::string::npos) << sentence;
}

// Pointers to each of `runs`, one group.
std::vector<const LearningResult*> group_of(const std::vector<LearningResult>& runs) {
  std::vector<const LearningResult*> group;
  for (const LearningResult& r : runs) group.push_back(&r);
  return group;
}

// Three paired seeds whose final losses overlap (Adam 0.1–0.3, HIG 0.05–0.25): the medians (0.15
// below 0.2) crown no winner, and the sentence says the ranges are not separated.
TEST(LearningVerdict, OverlappingSeedRangesAreNotSeparated) {
  const std::vector<LearningResult> adam = {run("adam", {1.0, 0.5, 0.1}, 100, 1e-3),
                                            run("adam", {1.0, 0.5, 0.2}, 100, 1e-3),
                                            run("adam", {1.0, 0.5, 0.3}, 100, 1e-3)};
  const std::vector<LearningResult> hig = {run("hig", {1.0, 0.5, 0.05}, 100, 1e-3),
                                           run("hig", {1.0, 0.5, 0.15}, 100, 1e-3),
                                           run("hig", {1.0, 0.5, 0.25}, 100, 1e-3)};
  const std::string sentence =
      verdict_sentence({{group_of(adam), group_of(hig)}, kTestLoss, "final test loss"});
  EXPECT_NE(sentence.find("HIG's and Adam's final test loss are not separated over 3 seeds "
                          "(medians 0.15 vs 0.2, ranges 0.05–0.25 vs 0.1–0.3 over 3 seeds)"),
            std::string::npos)
      << sentence;
  EXPECT_EQ(sentence.find("× below"), std::string::npos) << sentence;
  // The level is Adam's 0.2: each rule's third seed never reaches it, the others between 100 and
  // 200 updates.
  EXPECT_NE(sentence.find("(not separated over 3 seeds; medians, the seeds' brackets spanning "
                          "from 100 to never vs from 100 to never)"),
            std::string::npos)
      << sentence;
}

// Three paired seeds whose ranges are apart (HIG 0.01–0.03, Adam 0.1–0.3): the ratio of the
// medians, with both ranges; and the updates to reach Adam's 0.2 apart as well (HIG's seeds within
// their first 10, Adam's from 100 on, its third never).
TEST(LearningVerdict, SeparatedSeedRangesGiveTheRatioAndTheRanges) {
  const std::vector<LearningResult> adam = {run("adam", {1.0, 0.5, 0.1, 0.1}, 100, 1e-3),
                                            run("adam", {1.0, 0.5, 0.2, 0.2}, 100, 1e-3),
                                            run("adam", {1.0, 0.5, 0.4, 0.3}, 100, 1e-3)};
  const std::vector<LearningResult> hig = {run("hig", {1.0, 0.1, 0.01}, 10, 1e-3),
                                           run("hig", {1.0, 0.1, 0.02}, 10, 1e-3),
                                           run("hig", {1.0, 0.1, 0.03}, 10, 1e-3)};
  const std::string sentence =
      verdict_sentence({{group_of(adam), group_of(hig)}, kTestLoss, "final test loss"});
  EXPECT_NE(sentence.find("HIG's final test loss is 10× below Adam's (medians 0.02 vs 0.2, ranges "
                          "0.01–0.03 vs 0.1–0.3 over 3 seeds)"),
            std::string::npos)
      << sentence;
  EXPECT_EQ(sentence.find("not separated"), std::string::npos) << sentence;
  EXPECT_NE(sentence.find("to reach 0.2 HIG needs between 0 and 10 updates, Adam between 100 and "
                          "200 (at least 10× fewer; medians over 3 seeds, the seeds' brackets "
                          "spanning 0–10 vs from 100 to never)"),
            std::string::npos)
      << sentence;
}

// One run per rule: the sentence says so.
TEST(LearningVerdict, OneSeedIsSaid) {
  const LearningResult adam = run("adam", {1.0, 0.5, 0.1}, 100, 1e-3);
  const LearningResult hig = run("hig", {1.0, 0.1, 0.01}, 10, 1e-3);
  const LearningResult gn = run("gn", {1.0, 0.5, 0.4}, 10, 1e-3);
  const std::string sentence =
      verdict_sentence({{{&adam}, {&hig}, {&gn}}, kTestLoss, "final test loss"});
  EXPECT_NE(sentence.find("HIG's final test loss is 10× below Adam's (0.01 vs 0.1, one seed); "
                          "Gauss-Newton's is 0.4 (one seed)."),
            std::string::npos)
      << sentence;
  EXPECT_EQ(sentence.find("medians"), std::string::npos) << sentence;
}

TEST(LearningVerdict, RatiosCarryTwoSignificantDigits) {
  EXPECT_EQ(ratio_text(1.5), "1.5×");
  EXPECT_EQ(ratio_text(12.34), "12×");
  EXPECT_EQ(ratio_text(482.0), "480×");
  EXPECT_EQ(ratio_text(7712.0), "7700×");
  EXPECT_EQ(ratio_text(0.456), "0.46×");
  EXPECT_EQ(value_text(0.031234), "0.0312");
}

// After a lead ("After the same budget, ", "At ξ = 32, ") the verdict's own first word is in lower
// case unless it is a rule's label: a run whose every rule failed reads "After the same budget, no
// rule ended …", not "…, No rule ended …".
TEST(LearningVerdict, ALeadBeforeNoRuleReadsInLowerCase) {
  EXPECT_EQ(verdict_after("At ξ = 32, ", "No rule ended a run."),
            "At ξ = 32, no rule ended a run.");
  EXPECT_EQ(verdict_after("At ξ = 32, ", "HIG's final loss is 2× below Adam's."),
            "At ξ = 32, HIG's final loss is 2× below Adam's.");
  const RunContext failed = testing::run_experiment(
      "poisson", {{"grid", "4"}, {"train-size", "64"}, {"test-size", "16"}, {"seeds", "1"},
                  {"optimizers", "adam"}, {"lr", "1e300"}, {"iters", "3"}, {"pretrain", "0"}});
  EXPECT_NE(failed.message().find("After the same budget, no rule ended a run"),
            std::string::npos)
      << failed.message();
}

}  // namespace
}  // namespace physgrad::run
