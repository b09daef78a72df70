// Crossings in a learning verdict (run/crossing.hpp, run/learning_verdict.hpp): the updates and
// seconds to reach a level are quoted no finer than the evaluations that straddle it, the
// wall-time figure is measured at those evaluations and says so, a twin's step cost is its
// rule's own, and the ratio of two rules' finals keeps the digits of the table of finals.
#include <gtest/gtest.h>

#include <cmath>

#include "physgrad/run/pages/crossing.hpp"
#include "physgrad/run/cases/learning_runs.hpp"
#include "physgrad/run/pages/learning_verdict.hpp"

namespace physgrad::run {
namespace {

const auto kLoss = [](const TrainingRecord& r) { return r.test_loss; };

// A run of rule `id` evaluated at `iterations` with test losses `losses`, each update taking
// `seconds_per_update`, ended by its time budget.
LearningResult evaluated(const std::string& id, const std::vector<long long>& iterations,
                         const std::vector<double>& losses, double seconds_per_update) {
  LearningResult r;
  r.id = id;
  r.label = learning_run_label(id);
  for (std::size_t k = 0; k < losses.size(); ++k) {
    TrainingRecord record;
    record.iteration = iterations[k];
    record.train_seconds = static_cast<double>(iterations[k]) * seconds_per_update;
    record.train_loss = record.test_loss = losses[k];
    r.summary.history.push_back(record);
  }
  r.summary.iterations = r.summary.history.back().iteration;
  r.summary.train_seconds = r.summary.history.back().train_seconds;
  r.summary.termination = TrainingTermination::kTimeBudget;
  return r;
}

// Evaluations every `every` updates from 0 to `last`, the loss exp(−k/scale) at update k.
LearningResult exponential(const std::string& id, long long every, long long last, double scale,
                           double seconds_per_update) {
  std::vector<long long> at;
  std::vector<double> losses;
  for (long long k = 0; k <= last; k += every) {
    at.push_back(k);
    losses.push_back(std::exp(-static_cast<double>(k) / scale));
  }
  return evaluated(id, at, losses, seconds_per_update);
}

TEST(VerdictCrossing, BracketsTheLevelBetweenTheEvaluationsThatStraddleIt) {
  const LearningResult r = evaluated("adam", {0, 92, 184}, {1.0, 0.05, 0.01}, 0.5);
  const Crossing c = updates_crossing(r.summary, 0.1, kLoss);
  EXPECT_EQ(c.low, 0);
  EXPECT_EQ(c.high, 92);
  EXPECT_NEAR(c.estimate, 92 * std::log(10.0) / std::log(20.0), 1e-9);
  EXPECT_EQ(crossing_text(c), "between 0 and 92");
  EXPECT_FALSE(is_narrow(c));
  // Narrow: [3300, 3400] around 3347 reads in hundreds; width 0 is the evaluation itself.
  EXPECT_EQ(crossing_text({3300, 3400, 3347}), "3300");
  EXPECT_EQ(crossing_text({0.25, 0.26, 0.2551}), "0.26");
  EXPECT_EQ(crossing_text({0, 0, 0}), "0");
  EXPECT_EQ(crossing_text(updates_crossing(r.summary, 1e-3, kLoss)), "–");
  // The median of each end over seeds: the median crossing lies between them.
  const Crossing m = median_crossing({{0, 92, 23}, {92, 184, 100}, {NAN, NAN, NAN}});
  EXPECT_EQ(m.low, 92);
  EXPECT_EQ(m.high, 184);
  EXPECT_TRUE(std::isnan(median_crossing({{0, 92, 23}, {NAN, NAN, NAN}}).high));
}

TEST(VerdictCrossing, RatioRangesKeepOnlyTheDigitsBothEndsShare) {
  EXPECT_EQ(ratio_range_text(38.08, 38.4), "38×");
  EXPECT_EQ(ratio_range_text(38.08, 40), "40×");
  EXPECT_EQ(ratio_range_text(3.3, 7.9), "3.3–7.9×");
  EXPECT_EQ(ratio_range_text(9, INFINITY), "at least 9×");
  const RatioRange r = ratio_range({828, 920, 920}, {0, 92, 71});
  EXPECT_EQ(r.low, 9);
  EXPECT_TRUE(std::isinf(r.high));
  EXPECT_EQ(advantage_text(r, "fewer", "more", "same", "apart"), "at least 9× fewer");
  EXPECT_EQ(advantage_text(ratio_range({0, 62, 62}, {1, 2, 1.3}), "fewer", "more", "same", "apart"),
            "apart");
  EXPECT_EQ(advantage_text({0.2, 0.25}, "fewer", "more", "same", "apart"), "4–5× more");
  EXPECT_EQ(advantage_text({0.95, 1.05}, "fewer", "more", "same", "apart"), "same");
}

// sin-rotation-like: SIP evaluated at 0 and 92 comes below Adam's final 0.1 between them (an
// interpolation would say 70.7); Adam reaches it at its last evaluation, 920, after 828. The
// update counts are the brackets; in wall time SIP's bracket (0 to 9.2 s) contains Adam's.
TEST(VerdictCrossing, SparseEvaluationsGiveTheBracketNotAnInterpolatedCount) {
  std::vector<long long> at;
  std::vector<double> adam_losses;
  for (long long k = 0; k <= 10; ++k) {
    at.push_back(92 * k);
    adam_losses.push_back(std::pow(10.0, -0.1 * static_cast<double>(k)));
  }
  const LearningResult adam = evaluated("adam", at, adam_losses, 1e-3);
  const LearningResult sip = evaluated("sip", {0, 92, 184}, {1.0, 0.05, 0.01}, 0.1);
  const std::string sentence = verdict_sentence({{{&adam}, {&sip}}, kLoss, "final test loss"});
  EXPECT_NE(sentence.find("to reach 0.1 SIP needs between 0 and 92 updates, Adam 920 (at least "
                          "9× fewer)"),
            std::string::npos)
      << sentence;
  EXPECT_EQ(sentence.find("70.7"), std::string::npos) << sentence;
  EXPECT_NE(sentence.find("in wall time (measured at the same evaluations) the brackets do not "
                          "tell which gets there sooner (between 0 and 9.2 vs 0.92 s)"),
            std::string::npos)
      << sentence;
}

// poisson-like: Adam evaluated at 0 and 62 only; HIG crosses Adam's final 0.3 between its first
// and second update. Neither count is known closer than its bracket, and the brackets overlap:
// no ratio (an interpolation would say "47× fewer (1.3 vs 62)").
TEST(VerdictCrossing, OverlappingBracketsGiveNoRatio) {
  const LearningResult adam = evaluated("adam", {0, 62}, {1.0, 0.3}, 1e-3);
  const LearningResult hig = evaluated("hig", {0, 1, 2}, {1.0, 0.5, 0.1}, 0.05);
  const std::string sentence = verdict_sentence({{{&adam}, {&hig}}, kLoss, "final test loss"});
  EXPECT_NE(sentence.find("to reach 0.3 HIG needs between 1 and 2 updates, Adam between 0 and 62 "
                          "(the brackets do not tell which needs fewer)"),
            std::string::npos)
      << sentence;
  EXPECT_EQ(sentence.find("fewer updates"), std::string::npos) << sentence;
}

// hig-toy-like, densely evaluated: HIG reaches Adam's final e⁻⁵ at its evaluation 260 (after 250),
// Adam at 10000 (after 9900): both brackets are narrow, so the counts are quoted, rounded to
// their brackets' tens and hundreds, and the ratio with the digit both ends share (38–40: 40×).
TEST(VerdictCrossing, NarrowBracketsGiveRoundedCountsAndTheirRatio) {
  const LearningResult adam = exponential("adam", 100, 10000, 2000, 1e-4);
  const LearningResult hig = exponential("hig", 10, 400, 52, 1e-3);
  const std::string sentence = verdict_sentence({{{&adam}, {&hig}}, kLoss, "final test loss"});
  EXPECT_NE(sentence.find("HIG needs 260 updates, Adam 10000 (40× fewer); its update costs 10× "
                          "Adam's (seconds per update of the two runs); in wall time (measured at "
                          "the same evaluations) HIG gets there 4× sooner (0.26 vs 1.00 s)"),
            std::string::npos)
      << sentence;
}

// A twin's step cost is its rule's: Adam made 1000 updates at 1 ms, then HIG 10 at 1 s (40
// between its evaluations at 1000 and 1010). Over the whole run an update took 11 ms (11×
// Adam's); a HIG update costs 1000× Adam's.
TEST(VerdictCrossing, ATwinsStepCostIsItsRulesPhaseAlone) {
  const LearningResult adam = evaluated("adam", {0, 500, 1000, 1010}, {1.0, 0.5, 0.3, 0.29}, 1e-3);
  LearningResult twin = evaluated("adam-hig", {0, 500, 1000}, {1.0, 0.5, 0.3}, 1e-3);
  TrainingRecord after = twin.summary.history.back();
  after.iteration = 1010;
  after.train_seconds += 10;
  after.test_loss = after.train_loss = 0.01;
  twin.summary.history.push_back(after);
  twin.summary.iterations = 1010;
  twin.summary.train_seconds = after.train_seconds;
  twin.params = {{"switched", true}, {"pretrain_iterations", 1000}};
  EXPECT_NEAR(rule_seconds_per_update(twin), 1.0, 1e-12);
  EXPECT_NEAR(rule_seconds_per_update(adam), 1e-3, 1e-12);
  const std::string sentence = verdict_sentence({{{&adam}, {&twin}}, kLoss, "final test loss"});
  EXPECT_NE(sentence.find("its update after the switch costs 1000× Adam's (seconds per update"),
            std::string::npos)
      << sentence;
  // Without an evaluation after the switch there is no cost of the rule to state.
  twin.summary.history.pop_back();
  EXPECT_TRUE(std::isnan(rule_seconds_per_update(twin)));
}

// With cost probes the cost is theirs, not the ratio of the runs' seconds (10× here, which load
// could bias): a HIG update timed at 50 Adam updates beside its steps. The counts to the level in
// Adam-update equivalents follow: HIG's 250–260 updates are 12500–13000, against Adam's 10000.
TEST(VerdictCrossing, ProbedCostsGiveTheCostInAdamUpdatesAndTheEquivalents) {
  const LearningResult adam = exponential("adam", 100, 10000, 2000, 1e-4);
  LearningResult hig = exponential("hig", 10, 400, 52, 1e-3);
  hig.summary.phases = {{.first_iteration = 0, .batch_size = 32, .probes = 4, .reference_cpu_seconds = 1,
                         .timed_steps = 4, .step_cpu_seconds = 50}};
  EXPECT_DOUBLE_EQ(adam_updates_per_update(hig), 50);
  EXPECT_DOUBLE_EQ(adam_updates_per_update(adam), 1);
  const std::string sentence = verdict_sentence({{{&adam}, {&hig}}, kLoss, "final test loss"});
  EXPECT_NE(sentence.find("HIG needs 260 updates, Adam 10000 (40× fewer); its update costs 50 "
                          "Adam updates (timed beside its steps); in Adam-update equivalents "
                          "13000, Adam 10000 (1.3× more); in wall time"),
            std::string::npos)
      << sentence;
  EXPECT_EQ(sentence.find("seconds per update of the two runs"), std::string::npos) << sentence;
  // Equivalents are whole updates, also at a cost with decimals (100 / 3 Adam updates).
  hig.summary.phases[0].step_cpu_seconds = 100;
  hig.summary.phases[0].reference_cpu_seconds = 3;
  const std::string thirds = verdict_sentence({{{&adam}, {&hig}}, kLoss, "final test loss"});
  // 8333–8667 against 9900–10000: 1.14–1.2× fewer, which one digit would round to "1×".
  EXPECT_NE(thirds.find("in Adam-update equivalents 8700, Adam 10000 (1.1–1.2× fewer)"),
            std::string::npos)
      << thirds;
  EXPECT_EQ(thirds.find("e+0"), std::string::npos) << thirds;
}

// A twin's equivalents: its Adam updates count one each, its rule's updates after the switch at
// the rule's probed cost. Adam→HIG switched at 1000 and reached the level between 1000 and 1010
// updates, at 3000 Adam updates each after the switch: between 1000 and 31000 equivalents.
TEST(VerdictCrossing, ATwinsEquivalentsCountItsAdamPartOnceAndItsRulesAtTheirCost) {
  const LearningResult adam = evaluated("adam", {0, 500, 1000, 1010}, {1.0, 0.5, 0.3, 0.29}, 1e-3);
  LearningResult twin = evaluated("adam-hig", {0, 500, 1000, 1010}, {1.0, 0.5, 0.3, 0.01}, 1e-3);
  twin.params = {{"switched", true}, {"pretrain_iterations", 1000}};
  twin.summary.phases = {{.first_iteration = 0, .batch_size = 32},
                         {.first_iteration = 1000, .batch_size = 32, .probes = 3,
                          .reference_cpu_seconds = 0.01, .timed_steps = 3,
                          .step_cpu_seconds = 30}};
  EXPECT_DOUBLE_EQ(adam_updates_per_update(twin), 3000);
  const std::string sentence = verdict_sentence({{{&adam}, {&twin}}, kLoss, "final test loss"});
  EXPECT_NE(sentence.find("its update after the switch costs 3000 Adam updates (timed beside its "
                          "steps); in Adam-update equivalents between 1000 and 31000, Adam 1010 "),
            std::string::npos)
      << sentence;
}

// The level is compared as printed: Adam's curve hovers about its final 0.904637, which the
// sentence prints as 0.905, and already reads 0.90473 at update 184. Against the printed level
// Adam got there between 92 and 184, not between 368 and 460 as against the unprinted digits.
TEST(VerdictCrossing, TheLevelIsComparedAsPrinted) {
  const LearningResult adam =
      evaluated("adam", {0, 92, 184, 276, 368, 460},
                {1.0, 0.90561, 0.90473, 0.90486, 0.90476, 0.904637}, 1e-3);
  const LearningResult sip = evaluated("sip", {0, 92, 184, 276, 368, 460},
                                       {1.0, 0.5, 0.3, 0.2, 0.15, 0.1}, 1e-3);
  const std::string sentence = verdict_sentence({{{&adam}, {&sip}}, kLoss, "final test loss"});
  EXPECT_NE(sentence.find("to reach 0.905 SIP needs between 0 and 92 updates, Adam between 92 "
                          "and 184 "),
            std::string::npos)
      << sentence;
}

// The ratio of two rules' median finals keeps the digits their seeds' spreads support, as the
// table of finals does ("×50"): Gauss-Newton's finals range over two decades, so 45.45 reads 50
// (its seeds' range stays above HIG's, so the two are separated).
TEST(VerdictCrossing, TheRatioOfFinalsHasTheDigitsOfTheTableOfFinals) {
  std::vector<LearningResult> gn, hig;
  for (const double v : {0.007, 0.4, 0.01, 0.03, 0.3}) {
    gn.push_back(evaluated("gn", {0, 100}, {1.0, v}, 1e-3));
  }
  for (const double v : {0.00067, 0.0006, 0.0011, 0.00066, 0.00055}) {
    hig.push_back(evaluated("hig", {0, 100}, {1.0, v}, 1e-3));
  }
  std::vector<const LearningResult*> gn_group, hig_group;
  for (const LearningResult& r : gn) gn_group.push_back(&r);
  for (const LearningResult& r : hig) hig_group.push_back(&r);
  const std::string sentence =
      verdict_sentence({{gn_group, hig_group}, kLoss, "median final test loss"});
  EXPECT_NE(sentence.find("HIG's median final test loss is 50× below Gauss-Newton's (medians "
                          "0.00066 vs 0.03, ranges 0.00055–0.0011 vs 0.007–0.4 over 5 seeds)"),
            std::string::npos)
      << sentence;
}

}  // namespace
}  // namespace physgrad::run
