// Experiment checkpoints — the learning runs of one experiment, those finished (their summary
// and final θ) and the one in progress (its TrainerState), in OUT/checkpoint.pgc next to the
// resolved settings in OUT/config.json, so that `physgrad resume OUT` repeats the experiment's
// deterministic set-up, takes the finished runs from the file and continues the interrupted
// one where it stopped.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "physgrad/io/folder_handle.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad::run {

inline constexpr const char* kCheckpointFile = "checkpoint.pgc";

// Which learning run of an experiment: its position and what identifies it.
struct RunKey {
  long long index = 0;  // 0 for the experiment's first learning run
  std::string optimizer;
  std::string tag;
  long long seed = 0;

  nlohmann::json json() const;
  std::string describe() const;  // "run 3 (hig, λ=1, seed 2)"
};

struct FinishedRun {
  TrainingSummary summary;
  Vector parameters;
};

class ExperimentCheckpoint {
 public:
  // `folder` is the run folder the checkpoint file is written into, through its handle; without
  // one (the other ranks of a data-parallel run) nothing is written. `config` is the config.json
  // document of the run; `resumed` a checkpoint document read back with read_checkpoint_file()
  // (null for a fresh run). Throws Error when `resumed` is not the checkpoint of this experiment
  // with these settings. `folder` must outlive the checkpoint.
  ExperimentCheckpoint(const FolderHandle* folder, nlohmann::json config,
                       nlohmann::json resumed = nullptr);

  // The run `key` as the resumed checkpoint has it: finished, or in progress. Throws Error when
  // the checkpoint holds another run at this position or an invalid state.
  std::optional<FinishedRun> finished(const RunKey& key, Index parameter_count) const;
  std::optional<TrainerState> in_progress(const RunKey& key, Index parameter_count) const;

  // Both write the checkpoint file into the run folder (which exists: the RunFolder holds it).
  void record_finished(const RunKey& key, const TrainingSummary& summary, const Vector& theta);
  void save_progress(const RunKey& key, const TrainerState& state);

  // What besides the settings decides the last bits of the results (BLAS threads, ranks); it
  // is saved with every checkpoint. Returns, for a resumed checkpoint, "blas_threads 2 (now 1)"
  // for each entry that differs from `environment` (empty when all agree).
  std::string set_environment(nlohmann::json environment);

  bool written() const { return written_; }  // the folder has a checkpoint file

 private:
  void write(const nlohmann::json& current);

  const FolderHandle* folder_ = nullptr;
  nlohmann::json config_;
  nlohmann::json finished_ = nlohmann::json::array();
  nlohmann::json resumed_current_;  // the run in progress when the checkpoint was taken
  nlohmann::json resumed_environment_;
  nlohmann::json environment_ = nlohmann::json::object();
  bool written_ = false;
};

}  // namespace physgrad::run
