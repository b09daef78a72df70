// Run — the life of one experiment run as one call, for every front end (the CLI, tests, Python):
// claim the run folder → write config.json → run, saving checkpoints inside → commit the results,
// or abandon the folder as RunFolder::abandon() says; Run::resume continues an unfinished one.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "physgrad/parallel/communicator.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "physgrad/run/life/run_summary.hpp"

namespace physgrad::run {

class Registry;

// What a front end hands the run besides the settings; every member may stay empty.
struct RunHooks {
  // Each progress line as it comes (often), and the end of a sweep's lines; none: silent.
  std::function<void(const std::string&)> progress;
  std::function<void()> progress_end;
  // A progress line that stays: a run started or finished.
  std::function<void(const std::string&)> progress_event;
  // A notice to the user: "warning: the checkpoint was written with …", "DIR has no checkpoint; …".
  std::function<void(const std::string&)> log;
  // The command recorded in config.json (Run::resume keeps the recorded one).
  std::string command;
  // The ranks that train together (data-parallel learning); null: this process alone. Only
  // rank 0 claims and writes the folder; the other ranks compute their share.
  std::shared_ptr<Communicator> communicator;
};

struct RunOutcome {
  // False when the run stopped on request (SIGINT/SIGTERM through physgrad/stop.hpp's flag).
  bool finished = false;
  // The run folder as messages name it (as given, or where it is now when it was moved); empty on
  // the ranks that do not write.
  std::filesystem::path folder;
  // summary.json: how each rule's run ended (run_summary.hpp). None when the run stopped.
  std::optional<RunSummary> summary;
  // The experiment's tables (final losses, time per step, …), as the CLI prints them.
  std::vector<RunContext::Table> tables;
  std::filesystem::path report;  // FOLDER/report.html; empty when stopped or not writing
  // When stopped: "NAME: stopped on request; checkpoint kept, continue with: physgrad resume DIR".
  std::string stopped;
  int signal = 0;  // the signal that asked the stop, 0 when none did
};

class Run {
 public:
  // A new run of `experiment` with `settings` (resolve_settings()) into the folder `out`: absent
  // or empty; an empty `out` takes --out of the settings, or else a new folder
  // runs/NAME-<timestamp>[-N]. Throws Error (naming the folder and what was kept) when the
  // folder cannot be claimed or the run fails.
  static RunOutcome start(const Experiment& experiment, const Settings& settings,
                          const std::filesystem::path& out, const RunHooks& hooks = {});
  // Continues the unfinished run in `dir` with the settings of its config.json: from its
  // checkpoint, or from the start when it has none; its experiment is found by name in
  // `experiments` (the caller's: the CLI's built-in ones, or a program's own). Throws Error as
  // start() does, and naming config.json when it does not hold the settings of an experiment of
  // `experiments`.
  static RunOutcome resume(const Registry& experiments, const std::filesystem::path& dir,
                           const RunHooks& hooks = {});
};

}  // namespace physgrad::run
