// The index page of a folder of run folders (`physgrad report DIR`), a comparison page: per
// experiment, each folder's message sentence, a table of folder × rule by the metric the message
// compares (summary.json "message"; the final loss where a folder has none) with the options that
// differ from the experiment's defaults and the rules' colours, and that metric of every compared
// run vs training time overlaid (median over seeds with the min–max band, from metrics.csv); then
// every run of every folder with its final figures and a link to its report.
#pragma once

#include <cstddef>
#include <filesystem>
#include <iostream>

namespace physgrad::experiments {

// Writes DIR/index.html (atomically) over the run folders directly inside DIR (folders with a
// summary.json); returns how many it shows. Whatever the folders hold, reading them takes time
// linear in what is read and bounded memory, and no folder's content ends the index: a folder
// whose summary.json or config.json cannot be read (more than 8 MiB, not a regular file, not
// JSON) or has a field of the wrong type is left out, and a metrics.csv that cannot be read (more
// than 32 MiB, a header of more than 4096 cells, ragged) leaves out that folder's curves; of a
// summary only the first 10,000 runs are shown, of a metrics.csv the first 200,000 rows and 256
// curves (label and seed). What is left out is listed in the page and, one line each
// ("physgrad: warning: report: …"), on `warnings`. Throws Error when DIR is not a directory or
// holds no run folder that can be shown.
std::size_t write_run_index(const std::filesystem::path& dir, std::ostream& warnings = std::cerr);

}  // namespace physgrad::experiments
