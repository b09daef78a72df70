// The index page of a folder of run folders (`physgrad report DIR`): every run of every run
// folder with its final figures and a link to its report, and per experiment the loss curves of
// all its run folders overlaid (median over seeds with the min–max band, from metrics.csv).
#pragma once

#include <cstddef>
#include <filesystem>

namespace physgrad::experiments {

// Writes DIR/index.html (atomically) over the run folders directly inside DIR (folders with a
// summary.json); returns how many there are. Throws Error when DIR is not a directory, holds no
// run folder, or a run folder's summary.json or metrics.csv cannot be read (naming the file).
std::size_t write_run_index(const std::filesystem::path& dir);

}  // namespace physgrad::experiments
