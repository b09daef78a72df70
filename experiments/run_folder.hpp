// Run folder — turns a finished RunContext into config.json, metrics.csv, summary.json, SVG
// figures and report.html. Everything is written into a staging folder that is renamed into
// place at the end, so an interrupted or failed run never leaves a half-written folder.
#pragma once

#include <filesystem>
#include <string>

#include "experiment.hpp"

namespace physgrad::experiments {

// Checks that `out` can become the run folder (absent or an empty directory; with `resuming`,
// the folder of an interrupted run, whose checkpoint the caller has read) and creates the
// staging folder beside it. Throws Error
// naming the path and the reason otherwise.
std::filesystem::path prepare_run_folder(const std::filesystem::path& out, bool resuming = false);

// The config.json document: {"experiment", "command", "settings"}.
nlohmann::json config_document(const Experiment& experiment, const Settings& settings,
                               const std::string& command_line);

void write_run_folder(const std::filesystem::path& staging, const Experiment& experiment,
                      const Settings& settings, const RunContext& context,
                      const std::string& command_line);

// Moves the staging folder to `out`. An empty directory there is replaced; the folder of an
// interrupted run (config.json and its checkpoint) is swapped out in one atomic exchange and
// then removed.
void commit_run_folder(const std::filesystem::path& staging, const std::filesystem::path& out);
// Removes the staging folder; never throws.
void discard_run_folder(const std::filesystem::path& staging) noexcept;

// The summary.json document: {"experiment": NAME, "runs": [...]}.
nlohmann::json summary_document(const Experiment& experiment, const RunContext& context);

}  // namespace physgrad::experiments
