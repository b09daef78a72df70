// Crossing — where a run's evaluated curve first comes down to a level L: between the last
// evaluation above L and the first at or below it, [low, high], estimated log-linearly inside.
#pragma once

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "physgrad/train/trainer.hpp"

namespace physgrad::run {

// The bracket [low, high] of `progress` (updates, seconds) in which the curve reached the level,
// and the estimate inside it; all NaN when it never did. A curve that starts at or below the level
// has low = high = the first evaluation's progress.
struct Crossing {
  double low = NAN, high = NAN, estimate = NAN;
  bool reached() const { return !std::isnan(high); }
};

// The crossing of `value` (lower is better) over `progress` in `history`: the estimate is
// log-linear in the value between the bracketing evaluations (linear where a value is ≤ 0).
Crossing crossing_of(const std::vector<TrainingRecord>& history, double level,
                     const std::function<double(const TrainingRecord&)>& value,
                     const std::function<double(const TrainingRecord&)>& progress);

// The updates and the training seconds in which a run brought `value` down to `level`: the
// bracket between the evaluations that straddle it and the estimate inside (crossing_of).
Crossing updates_crossing(const TrainingSummary& run, double level,
                          const std::function<double(const TrainingRecord&)>& value);
Crossing seconds_crossing(const TrainingSummary& run, double level,
                          const std::function<double(const TrainingRecord&)>& value);
// The estimates alone (interpolated between evaluations, log-linearly in the value); NaN when it
// never did.
double updates_to_reach(const TrainingSummary& run, double level,
                        const std::function<double(const TrainingRecord&)>& value);
double seconds_to_reach(const TrainingSummary& run, double level,
                        const std::function<double(const TrainingRecord&)>& value);

// The median over runs of each of low, high and estimate, a run that never got there counting as
// the largest: NaN when fewer than half the runs got there. The median crossing lies in the
// bracket of the medians, since a median is monotone in each value.
Crossing median_crossing(const std::vector<Crossing>& runs);

// A bracket no wider than 10 % of its estimate (or of width 0).
bool is_narrow(const Crossing& c);

// "280" for a narrow bracket (the estimate rounded to the bracket's resolution, the power of 10
// at or below its width: [3300, 3400] gives hundreds), else "between 0 and 92"; "–" when never.
std::string crossing_text(const Crossing& c);

// The range of a / b over the two brackets, [a.low / b.high, a.high / b.low] (high = ∞ when b may
// be 0); both NaN when b is exactly 0 or either never got there.
struct RatioRange {
  double low = NAN, high = NAN;
};
RatioRange ratio_range(const Crossing& a, const Crossing& b);

// A ratio range with no digit the brackets do not support: "36×" when both ends read so at two
// significant digits, "40×" when they agree at one (but not "1×": 1.1–1.2× stays so), else
// "30–40×"; "at least 33×" for an open upper end.
std::string ratio_range_text(double low, double high);

// How `r` = a / b compares a's count with b's: "36× fewer" (low ≥ 1.1), "2× more" (high ≤
// 1/1.1), `same` (both ends within 10 % of 1) or `apart` (the brackets do not tell).
std::string advantage_text(const RatioRange& r, const std::string& fewer, const std::string& more,
                           const std::string& same, const std::string& apart);

}  // namespace physgrad::run
