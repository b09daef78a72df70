// The run folder's report.html: the experiment's captioned tables and notes, its figures, every
// run's start and end figures, and the settings — one self-contained page.
#pragma once

#include <string>
#include <string_view>

#include "physgrad/io/folder_handle.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "physgrad/run/life/run_summary.hpp"

namespace physgrad::run {

// The page of a finished run; `index_exists`: link ../index.html; `machine`: summary.json's;
// `metrics`: the folder's metrics.csv, whose runs the interactive comparison shows (none: empty).
std::string report_page_html(const Experiment& experiment, const Settings& settings,
                             const RunContext& context, const std::string& command_line,
                             bool index_exists, const nlohmann::json& machine,
                             std::string_view metrics = {});

// Writes report.html of the finished run (its `summary`) into `staging`, through its handle,
// linking ../index.html when the run folder's parent has one.
void write_report_file(const FolderHandle& staging, const Experiment& experiment,
                       const Settings& settings, const RunContext& context,
                       const std::string& command_line, const RunSummary& summary);

// A number of a summary or settings document: an integer (seed, iterations, batch) in full, any
// other number with 4 significant digits; "–" for null.
std::string format_number(const nlohmann::json& value);

// A setting's value as the command line takes it: whole numbers as integers ("10000"), other
// numbers as the shortest text that reads back exactly, lists joined by commas, "unset" for none.
std::string option_value_text(const nlohmann::json& value);

// "physgrad run NAME --option value …": every set option but --out (so that each run of it
// writes a fresh folder under runs/), values as option_value_text() gives them, shell-quoted
// where needed.
std::string reproduce_command(const Experiment& experiment, const Settings& settings);

}  // namespace physgrad::run
