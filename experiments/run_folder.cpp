#include "run_folder.hpp"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <unistd.h>

#include <cerrno>
#include <set>
#include <system_error>

#include "checkpoint.hpp"
#include "report_page.hpp"
#include "physgrad/error.hpp"
#include "physgrad/report/atomic_file.hpp"
#include "physgrad/report/csv.hpp"

namespace physgrad::experiments {

namespace fs = std::filesystem;

namespace {

std::string reason(const std::error_code& error) { return error.message(); }

CsvCell to_cell(const nlohmann::json& value) {
  if (value.is_number_integer()) return value.get<long long>();
  if (value.is_number()) return value.get<double>();
  if (value.is_string()) return value.get<std::string>();
  if (value.is_null()) return std::string();
  return value.dump();
}

std::string metrics_csv(const RunContext& context) {
  std::vector<std::string> columns;
  std::set<std::string> seen;
  for (const nlohmann::json& row : context.metrics()) {
    // nlohmann::json sorts object keys; the fixed leading columns come first.
    for (const char* key : {"label", "optimizer", "iteration", "epoch", "wall_seconds"}) {
      if (row.contains(key) && seen.insert(key).second) columns.emplace_back(key);
    }
    for (const auto& [key, value] : row.items()) {
      if (seen.insert(key).second) columns.push_back(key);
    }
  }
  CsvTable table(columns);
  for (const nlohmann::json& row : context.metrics()) {
    std::vector<CsvCell> cells;
    for (const std::string& column : columns) {
      cells.push_back(row.contains(column) ? to_cell(row.at(column)) : CsvCell(std::string()));
    }
    table.add_row(std::move(cells));
  }
  return table.str();
}

// Removes staging folders `prefix`PID left by processes that no longer exist (killed before
// they could clean up).
void remove_abandoned_staging(const fs::path& parent, const std::string& prefix) {
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(parent, error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const auto pid = static_cast<pid_t>(std::stol(digits));
    if (::kill(pid, 0) != 0 && errno == ESRCH) fs::remove_all(entry.path(), error);
  }
}

}  // namespace

fs::path prepare_run_folder(const fs::path& out, bool resuming) {
  std::error_code error;
  const std::string name = std::string("'") + out.string() + "'";
  if (!resuming && fs::exists(out, error)) {
    if (!fs::is_directory(out, error)) {
      throw Error("--out: " + name + " exists and is not a directory");
    }
    if (fs::exists(out / kCheckpointFile, error)) {
      throw Error("--out: " + name + " holds an interrupted run; continue it with `physgrad " +
                  "resume " + out.string() + "` or choose another folder");
    }
    if (!fs::is_empty(out, error)) {
      throw Error("--out: " + name + " already exists and is not empty");
    }
  }
  const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
  fs::create_directories(parent, error);
  if (error) {
    throw Error("--out: cannot create '" + parent.string() + "': " + reason(error));
  }
  const std::string prefix = std::string(".") + out.filename().string() + ".partial-";
  remove_abandoned_staging(parent, prefix);
  const fs::path staging = parent / (prefix + std::to_string(getpid()));
  fs::remove_all(staging, error);
  if (!fs::create_directory(staging, error) || error) {
    throw Error("--out: cannot write in '" + parent.string() + "': " +
                (error ? reason(error) : "staging folder exists"));
  }
  return staging;
}

nlohmann::json config_document(const Experiment& experiment, const Settings& settings,
                               const std::string& command_line) {
  return {{"experiment", experiment.name()},
          {"command", command_line},
          {"settings", settings.json()}};
}

nlohmann::json summary_document(const Experiment& experiment, const RunContext& context) {
  return {{"experiment", experiment.name()}, {"runs", context.runs()}};
}

void write_run_folder(const fs::path& staging, const Experiment& experiment,
                      const Settings& settings, const RunContext& context,
                      const std::string& command_line) {
  write_file_atomic(staging / "config.json",
                    config_document(experiment, settings, command_line).dump(2) + "\n");
  write_file_atomic(staging / "metrics.csv", metrics_csv(context));
  write_file_atomic(staging / "summary.json", summary_document(experiment, context).dump(2) + "\n");
  for (const RunContext::Figure& figure : context.figures()) {
    write_file_atomic(staging / figure.file, figure.svg);
  }
  if (!context.networks().empty()) {
    write_file_atomic(staging / "networks.json",
                      nlohmann::json{{"networks", context.networks()}}.dump() + "\n");
  }
  write_file_atomic(staging / "report.html",
                    report_page_html(experiment, settings, context, command_line));
}

void commit_run_folder(const fs::path& staging, const fs::path& out) {
  std::error_code error;
  if (fs::exists(out, error) && !fs::is_empty(out, error)) {
    // An interrupted run's folder: exchange it with the results at once, then drop it.
    if (::renameat2(AT_FDCWD, staging.c_str(), AT_FDCWD, out.c_str(), RENAME_EXCHANGE) == 0) {
      fs::remove_all(staging, error);
      return;
    }
    if (errno != EINVAL && errno != ENOSYS) {
      throw Error("--out: cannot move the results to '" + out.string() +
                  "': " + std::generic_category().message(errno));
    }
    fs::remove_all(out, error);  // a file system without atomic exchange
  }
  if (fs::exists(out, error)) fs::remove(out, error);  // an empty directory, checked before
  fs::rename(staging, out, error);
  if (error) {
    throw Error("--out: cannot move the results to '" + out.string() + "': " + reason(error));
  }
}

void discard_run_folder(const fs::path& staging) noexcept {
  std::error_code error;
  fs::remove_all(staging, error);
}

}  // namespace physgrad::experiments
