#include "physgrad/run/run.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cstdlib>
#include <ctime>
#include <iomanip>
#include <optional>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/io/atomic_file.hpp"
#include "physgrad/io/checkpoint_file.hpp"
#include "physgrad/parallel/distributed_eigen.hpp"
#include "physgrad/run/cases/registry.hpp"
#include "physgrad/run/life/checkpoint.hpp"
#include "physgrad/run/life/config_file.hpp"
#include "physgrad/run/life/interrupt.hpp"
#include "physgrad/run/life/run_folder.hpp"
#include "physgrad/run/pages/report_page.hpp"
#include "physgrad/threads.hpp"
#include "life/fault_point.hpp"

namespace physgrad::run {

namespace {

std::string timestamp() {
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  std::ostringstream out;
  out << std::put_time(&local, "%Y%m%d-%H%M%S");
  return out.str();
}

std::shared_ptr<Communicator> communicator_of(const RunHooks& hooks) {
  return hooks.communicator ? hooks.communicator : std::make_shared<SerialCommunicator>();
}

void log(const RunHooks& hooks, const std::string& text) {
  if (hooks.log) hooks.log(text);
}

// Claims the folder of a new run (see Run::start); only the writing rank claims one.
std::optional<RunFolder> claim_new_folder(const Experiment& experiment, const Settings& settings,
                                          const std::filesystem::path& out, bool writer) {
  if (!writer) return std::nullopt;
  if (!out.empty()) return RunFolder::create(locate_folder(out.string(), "--out"));
  if (settings.has("out")) return RunFolder::create(locate_folder(settings.text("out"), "--out"));
  return RunFolder::create_unique("runs", experiment.name() + "-" + timestamp());
}

// Runs `experiment` into `folder` (absent on the ranks that do not write): writes config.json
// into a new one, or continues the checkpoint `resumed` when it is not null. Everything the run
// writes goes through the folder's handle. Whatever ends the run, the folder is committed or
// left as RunFolder::abandon() says.
RunOutcome run_in(const Experiment& experiment, const Settings& settings,
                  const std::string& command, std::optional<RunFolder>& folder,
                  const RunHooks& hooks, const nlohmann::json& resumed = nullptr) {
  // One BLAS thread unless asked: the matrices of most runs are small, and a multithreaded
  // BLAS on busy cores costs more than it saves.
  if (settings.has("threads")) {
    set_blas_threads(static_cast<int>(settings.integer("threads")));
  } else if (std::getenv("OPENBLAS_NUM_THREADS") == nullptr &&
             std::getenv("OMP_NUM_THREADS") == nullptr) {
    set_blas_threads(1);
  }
  set_distributed_gram_rows(settings.has("distributed-gram-rows")
                                ? settings.integer("distributed-gram-rows")
                                : kDefaultDistributedGramRows);
  const std::shared_ptr<Communicator> communicator = communicator_of(hooks);
  const bool writer = folder.has_value();
  const nlohmann::json config = config_document(experiment, settings, command);
  RunOutcome outcome;
  try {
    if (writer && !folder->resuming()) {
      write_file_atomic(folder->handle(), kConfigFile, config.dump(2) + "\n");
      fault_point("claimed");
    }
    ExperimentCheckpoint checkpoint(writer ? &folder->handle() : nullptr, config, resumed);
    const std::string changed = checkpoint.set_environment(
        {{"blas_threads", blas_threads()}, {"ranks", communicator->size()}});
    if (!changed.empty() && writer) {
      log(hooks, "warning: the checkpoint was written with " + changed +
                     "; the continued run may differ from an uninterrupted one in the last bits");
    }
    if (const std::string note = blas_core_note(); !note.empty() && writer) log(hooks, note);
    RunContext context;
    context.set_experiment_name(experiment.name());
    context.set_stop_flag(&stop_flag());
    context.set_checkpoint(&checkpoint);
    context.set_communicator(communicator);
    if (writer) context.set_progress(hooks.progress, hooks.progress_end, hooks.progress_event);
    experiment.run(settings, context);
    outcome.finished = true;
    outcome.summary = run_summary(experiment, context);
    outcome.tables = context.tables();
    if (!writer) return outcome;
    const FolderHandle& staging = folder->staging();  // made anew by each call
    write_run_folder(staging, experiment, settings, context, command, *outcome.summary);
    write_report_file(staging, experiment, settings, context, command, *outcome.summary);
    folder->commit();
    outcome.folder = folder->shown_now();
    outcome.report = outcome.folder / kReportFile;
  } catch (const Interrupted& e) {
    // A rank that stopped answering (RanksNotAnswering, or a training run that ended on it and
    // saved its checkpoint) is an error, not a stop: the job cannot go on.
    if (const std::string lost = communicator->failure(); !lost.empty()) {
      throw Error(writer ? lost + "; " + folder->abandon() : lost);
    }
    outcome = RunOutcome{};
    outcome.signal = received_signal();
    outcome.stopped = e.what();
    if (writer) {
      outcome.stopped += "; " + folder->abandon();
      outcome.folder = folder->shown_now();
    }
  } catch (const std::exception& e) {
    if (!writer) throw;
    throw Error(std::string(e.what()) + "; " + folder->abandon());
  }
  return outcome;
}

}  // namespace

RunOutcome Run::start(const Experiment& experiment, const Settings& settings,
                      const std::filesystem::path& out, const RunHooks& hooks) {
  const bool writer = communicator_of(hooks)->rank() == 0;
  std::optional<RunFolder> folder = claim_new_folder(experiment, settings, out, writer);
  return run_in(experiment, settings, hooks.command, folder, hooks);
}

RunOutcome Run::resume(const Registry& experiments, const std::filesystem::path& dir,
                       const RunHooks& hooks) {
  const FolderPath where = locate_folder(dir.string(), "resume");
  std::optional<RunFolder> folder;
  FolderHandle unclaimed;  // the other ranks read the folder without claiming it
  if (communicator_of(hooks)->rank() == 0) {
    folder.emplace(RunFolder::reopen(where));
    fault_point("claimed");
  } else {
    unclaimed = FolderHandle::open(where.path, where.shown);
  }
  const FolderHandle& handle = folder ? folder->handle() : unclaimed;
  const nlohmann::json config = read_config_document(handle, kConfigFile);
  // The saved settings are read as a config file would be, errors naming the file.
  const Experiment* experiment = nullptr;
  std::optional<Settings> settings;
  try {
    if (!config.is_object() || !config.contains("experiment") || !config["experiment"].is_string()) {
      throw Error("names no experiment");
    }
    experiment = &experiments.find(config["experiment"].get<std::string>());
    OptionTexts given = config_options(*experiment, config);
    given.emplace_back("out", where.shown);
    settings.emplace(resolve_settings(*experiment, given));
  } catch (const Error& e) {
    throw Error("resume: '" + handle.shown(kConfigFile) + "': " + e.what());
  }
  nlohmann::json resumed;
  if (::faccessat(handle.fd(), kCheckpointFile, F_OK, 0) == 0) {
    resumed = read_checkpoint_file(handle, kCheckpointFile);
  } else if (folder) {
    log(hooks, where.shown + " has no checkpoint; the run starts again from the beginning with "
                             "its saved settings");
  }
  const std::string command = config.contains("command") && config["command"].is_string()
                                  ? config["command"].get<std::string>()
                                  : "";
  return run_in(*experiment, *settings, command, folder, hooks, resumed);
}

}  // namespace physgrad::run
