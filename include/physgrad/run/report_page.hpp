// The run folder's report.html: the experiment's captioned tables and notes, its figures, every
// run's start and end figures, and the settings — one self-contained page.
#pragma once

#include <string>

#include "physgrad/run/experiment.hpp"

namespace physgrad::run {

std::string report_page_html(const Experiment& experiment, const Settings& settings,
                             const RunContext& context, const std::string& command_line);

// A number of a summary or settings document with 4 significant digits ("–" for null).
std::string format_number(const nlohmann::json& value);

}  // namespace physgrad::run
