// The data of the interactive comparison (report/compare_view.hpp) from a metrics.csv: a run per
// (label, seed) and each restart of its iteration count (another setting), the numeric columns
// as arrays, thinned to at most kCompareMaxPoints points per run (every k-th row, the first and
// the last kept), at most kCompareMaxRuns runs per file.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace physgrad::run {

inline constexpr std::size_t kCompareMaxPoints = 2000;
inline constexpr std::size_t kCompareMaxRuns = 256;

// The runs of `csv_text` as JSON objects {"g": group, "l": label, "s": seed, "c": {column:
// [values]}} (non-finite values null), comma-separated, each through json_for_script; empty
// when the text holds no run. What is left out (runs beyond kCompareMaxRuns) goes to `notes`
// ("more than 256 runs, …", for the caller to name the file).
// Throws Error (from parse_csv) on a ragged file.
std::string compare_runs_json(const std::string& group, std::string_view csv_text,
                              std::vector<std::string>& notes);

}  // namespace physgrad::run
