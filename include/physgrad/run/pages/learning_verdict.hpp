// Learning verdict — the sentence under a learning experiment's message figure: which rule ends
// lowest in the same budget, and per rule against Adam the update advantage N (Adam's updates to
// reach a level over the rule's, within the evaluations' brackets), the step cost C in Adam
// updates timed beside the rule's steps in its own process (so that machine load does not count),
// the Adam-update equivalents to the level, and the wall time to it measured at the same
// evaluations, shown but never the only judge.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "physgrad/report/significant.hpp"
#include "physgrad/run/pages/crossing.hpp"
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

// Per rule (group): the median and spread over its credited runs of the final value, and the
// medians of the seconds per update of the rule (rule_seconds_per_update, learning_runs.hpp) and
// of its cost in Adam updates (adam_updates_per_update); the counts of credited and of other runs.
struct RuleStanding {
  std::string label;
  std::string id;
  double final_value = NAN;
  Spread finals;  // of the final values, whose digits the ratio of two rules' medians keeps
  // The upper median of the finals (the median for an odd count): a level that at least half the
  // runs reached, so that the median of their counts to reach it is a number for any seed count.
  double reach_level = NAN;
  double seconds_per_update = NAN;
  double adam_updates = NAN;  // NaN unless every credited run has its probes
  int credited = 0, failed = 0;
  bool never_switched = false;  // a twin whose rule never took over
  bool twin = false;            // a rule that follows Adam (its cost is its own phase's)
  bool control = false;         // the control arm Adam→Adam (is_control_run)
};
RuleStanding standing(const std::vector<const LearningResult*>& group,
                      const std::function<double(const TrainingRecord&)>& value);

// A verdict sentence after `lead` ("After the same budget, ", "At ξ = 32, "): its first word in
// lower case where it is not a rule's label ("No rule ended …" reads "no rule ended …").
std::string verdict_after(const std::string& lead, std::string sentence);

// A ratio with two significant digits ("12×", "1.5×", "480×"), a value with three.
std::string ratio_text(double ratio);
std::string value_text(double value);

// The sentence: "HIG's final test loss is 12× below Adam's (0.031 vs 0.37); …. Per update and per
// second against Adam: to reach 0.37 HIG needs between 100 and 200 updates, Adam 3300 (17–33×
// fewer); its update costs 480 Adam updates (timed beside its steps); in Adam-update equivalents
// between 48000 and 96000, Adam 3300 (15–29× more); in wall time (measured at the same evaluations)
// Adam gets there 10–20× sooner (between 48 and 96 vs 4.7 s). …" Without cost probes the cost reads
// as the ratio of the two runs' seconds per update and the equivalents are left out. The ratio of
// two rules' finals is the ratio of their medians with the digits their spreads support (as the
// table of finals); counts, seconds and their ratios carry no digit finer than the evaluations'
// brackets. Failed runs are counted and never ranked; values within 10 % of each other are called
// about equal. Every comparison says over how many seeds it is ("one seed"); over several it gives
// the medians and the range of the seeds (min–max, for a count or seconds to reach the level from
// the lowest to the highest bracket end), and where the two rules' ranges overlap it names no
// winner: "not separated over 3 seeds". With a ranked control arm (Adam→Adam,
// RuleStanding::control), each ranked twin's final value is set against it: "After the same switch,
// Adam→HIG ends 1.3× below the control Adam→Adam (lr ×0.1) (0.05 vs 0.065)."
std::string verdict_sentence(const VerdictInput& input);

}  // namespace physgrad::run
