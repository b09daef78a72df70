// Learning verdict — the sentence under a learning experiment's message figure: which rule ends
// lowest in the same budget, and per rule against Adam the update advantage N (Adam's updates to
// reach a level over the rule's) and the step-cost ratio M, so that it wins in wall time where M < N.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "physgrad/train/trainer.hpp"

namespace physgrad::run {

struct LearningResult;

// A run counts in a verdict when a limit ended it (not a numerical failure, a divergence or a
// stop) and, for a rule that switches from Adam, when it switched: a twin that never did is
// Adam's run and is not ranked as the rule.
bool credited(const LearningResult& run);

// Every rule's runs (one group per rule, over seeds) and what is compared: `value` of an
// evaluation (lower is better; the test loss, say), named `what` ("final test loss").
struct VerdictInput {
  std::vector<std::vector<const LearningResult*>> groups;
  std::function<double(const TrainingRecord&)> value;
  std::string what;
};

// Per rule (group): the median over its credited runs of the final value, of the updates and the
// training seconds to reach `level` (NaN where fewer than half the runs reached it) and of the
// seconds per update; the counts of credited and of other runs.
struct RuleStanding {
  std::string label;
  std::string id;
  double final_value = NAN;
  // The upper median of the finals (the median for an odd count): a level that at least half the
  // runs reached, so that the median of their counts to reach it is a number for any seed count.
  double reach_level = NAN;
  double seconds_per_update = NAN;
  int credited = 0, failed = 0;
  bool never_switched = false;  // a twin whose rule never took over
};
RuleStanding standing(const std::vector<const LearningResult*>& group,
                      const std::function<double(const TrainingRecord&)>& value);

// The updates (interpolated between evaluations, log-linearly in the value) and the training
// seconds a run took to bring `value` down to `level`; NaN when it never did.
double updates_to_reach(const TrainingSummary& run, double level,
                        const std::function<double(const TrainingRecord&)>& value);
double seconds_to_reach(const TrainingSummary& run, double level,
                        const std::function<double(const TrainingRecord&)>& value);

// A ratio with two significant digits ("12×", "1.5×", "480×"), a value with three.
std::string ratio_text(double ratio);
std::string value_text(double value);

// The sentence: "HIG's final test loss is 12× below Adam's (0.031 vs 0.37); …. Per update and per
// second against Adam: to reach 0.37 HIG needs 35× fewer updates (94 vs 3300); its update costs
// 480× Adam's (M > N), so in wall time Adam gets there 14× sooner (0.9 vs 13 s). …" Failed runs are
// counted and never ranked; values within 10 % of each other are called about equal.
std::string verdict_sentence(const VerdictInput& input);

}  // namespace physgrad::run
