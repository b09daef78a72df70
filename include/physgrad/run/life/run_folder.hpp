// Run folder — the folder a run owns from its start to its end. It is claimed under an exclusive
// lock (flock on the folder itself, released by the kernel even when the process is killed), so
// no two processes ever write one folder; config.json is written at once, checkpoints go inside,
// and the results are staged in OUT/.staging and moved in file by file, summary.json last, the
// checkpoint removed after it. A folder is therefore always in one of four states, whatever
// moment a run is killed at:
//   empty       nothing of a run (scratch of a killed one aside): a new run may take it;
//   unfinished  config.json, checkpoint.pgc if a learning run saved one, and the results a commit
//               cut short moved in: `physgrad resume` continues it (from the start of the run
//               when there is no checkpoint);
//   finished    summary.json and no checkpoint: never written again;
//   foreign     anything else: refused.
// Every write, rename and removal of a run goes through the handle of the folder it claimed
// (openat, renameat, unlinkat), never through its path: when the folder is renamed mid-run and
// another one put at its path, the run's files follow the folder it claimed and the other one is
// not touched. Nothing is ever removed but the run's own files, and only while the lock is held.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "physgrad/io/folder_handle.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "physgrad/run/life/run_summary.hpp"

namespace physgrad::run {

inline constexpr const char* kConfigFile = "config.json";  // kSummaryFile: run_summary.hpp
inline constexpr const char* kMetricsFile = "metrics.csv";
inline constexpr const char* kReportFile = "report.html";

// A path a user typed, checked and resolved: not blank, no control characters, trailing slashes
// dropped, symbolic links to folders followed (a dangling or looping link, or a file, is refused).
struct FolderPath {
  std::string shown;           // as typed, without trailing slashes: used in messages
  std::filesystem::path path;  // absolute, symbolic links resolved
};
// `option` names the value in messages ("--out", "resume"). Throws Error.
FolderPath locate_folder(const std::string& text, const std::string& option);

class RunFolder {
 public:
  // Claims the folder for a new run: absent (it is created, with missing parents) or empty.
  // Throws Error naming the folder when it holds a run, anything else, or another process
  // uses it; nothing is changed then.
  static RunFolder create(const FolderPath& out);
  // Claims a new folder PARENT/STEM, or PARENT/STEM-2, -3, … when that one exists (the default
  // --out: two runs started in the same second get a folder each).
  static RunFolder create_unique(const std::filesystem::path& parent, const std::string& stem);
  // Claims the folder of an unfinished run for `physgrad resume`. Throws Error when it is
  // finished, holds no run, holds a file that is not the run's, or another process uses it.
  static RunFolder reopen(const FolderPath& folder);

  RunFolder(RunFolder&& other) noexcept;
  RunFolder& operator=(RunFolder&&) = delete;
  ~RunFolder();  // abandon() unless committed, then releases the lock

  // The claimed folder, locked: what the run writes and reads goes through it.
  const FolderHandle& handle() const { return folder_; }
  const std::string& shown() const { return folder_.shown(); }
  // The folder as messages name it: as typed, or where it is now when it has been moved since it
  // was claimed.
  std::string shown_now() const;
  bool resuming() const { return resuming_; }

  // An empty folder OUT/.staging for the results (made anew on each call).
  const FolderHandle& staging();
  // Moves the staged files into the folder (summary.json last), then removes the checkpoint
  // and the staging folder: the folder is finished.
  void commit();
  // Ends a run that will not commit and says what is left: the folder with its checkpoint (or,
  // when resuming, as it was) for `physgrad resume`, or nothing — the files of the run, the
  // folder and the parents this process created are removed. Never throws; the second call
  // returns the first one's text.
  std::string abandon() noexcept;

 private:
  RunFolder(const FolderPath& where, FolderHandle folder, bool resuming);
  // Throws Error "'FOLDER': cannot STEP: REASON" (err: the errno of the failed call), the folder
  // named where it is now (shown_now()).
  [[noreturn]] void fail(const std::string& step, int err) const;

  std::filesystem::path path_;  // where the folder was claimed (it may be moved since)
  FolderHandle folder_;         // holds the lock
  FolderHandle staging_;
  bool resuming_ = false;
  bool created_ = false;                              // this process made the folder
  std::vector<std::filesystem::path> created_parents_;  // innermost first
  std::vector<std::string> moved_;                      // results moved in by commit()
  bool ended_ = false;
  std::string ended_text_;
};

// The config.json document: {"experiment", "command", "settings"}.
nlohmann::json config_document(const Experiment& experiment, const Settings& settings,
                               const std::string& command_line);

// Writes config.json, metrics.csv, summary.json, the figures and networks.json into `staging`,
// through its handle; report.html is the pages' (write_report_file, report_page.hpp).
void write_run_folder(const FolderHandle& staging, const Experiment& experiment,
                      const Settings& settings, const RunContext& context,
                      const std::string& command_line, const RunSummary& summary);
// True for the name of a file a run writes into its folder when it commits (write_run_folder,
// report.html): what a commit cut short leaves in an unfinished folder besides config.json and
// the checkpoint.
bool is_result_file(const std::string& name);

// metrics.csv: one row per run × evaluation, the columns label, optimizer, iteration, epoch,
// wall_seconds first, then the others in the order first seen.
std::string metrics_csv(const RunContext& context);

// The summary of the finished run: the context's runs and message, and run_machine().
RunSummary run_summary(const Experiment& experiment, const RunContext& context);

}  // namespace physgrad::run
