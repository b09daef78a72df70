// The index page of a folder of run folders (`physgrad report DIR`), a comparison page: per
// experiment, each folder's message sentence, a table of folder × rule by the metric the message
// compares (summary.json "message"; the final loss where a folder has none) — the median over
// the runs that count, failed runs counted apart and never ranked — with the options that differ
// from the experiment's defaults and the rules' colours, and the compared runs' curves on the
// experiment's own axes (learning: against updates and against training time; direct
// optimization: against iterations or simulator passes); then the interactive comparison of every
// run of every folder (report/compare_view.hpp, run_compare_data.hpp) and every run of every
// folder with a link to its report.
#pragma once

#include <cstddef>
#include <filesystem>
#include <iostream>

namespace physgrad::run {

class Registry;

struct RunIndex {
  std::size_t folders = 0;      // the run folders shown
  std::filesystem::path page;  // DIR/index.html, or DIR/index-2.html, … when a folder has that name
};

// Writes DIR/index.html (atomically) over the run folders directly inside DIR (folders with a
// summary.json; when one of them is named index.html, the page is index-2.html). The folders are
// read one at a time and reduced to a digest of bounded size (run_index_folder.hpp), so memory
// grows only with the page; whatever the folders hold, reading them takes time linear in what is
// read, and no folder's content ends the index: a folder whose summary.json or config.json cannot
// be read (more than 8 MiB, not a regular file, not JSON) or has a field of the wrong type is left
// out, and a metrics.csv that cannot be read (more than 32 MiB, a header of more than 4096 cells,
// ragged) leaves out that folder's curves; of a summary only the first 10,000 runs are read, 100
// rows of label and setting listed and 64 labels compared, of a metrics.csv the first 200,000
// rows and 256 curves (label and seed), and the curves of the first 5 folders of an experiment
// are drawn. What is left out is listed in the page and, one line each ("physgrad: warning:
// report: …"), on `warnings`. Throws Error when DIR is not a directory or holds no run folder
// that can be shown.
// The options that differ from an experiment's defaults are those of its namesake in
// `experiments` (a folder of an experiment it does not hold shows every option).
RunIndex write_run_index(const Registry& experiments, const std::filesystem::path& dir,
                         std::ostream& warnings = std::cerr);

}  // namespace physgrad::run
