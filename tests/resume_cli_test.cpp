// Interrupted runs end to end: a learning run killed part-way (SIGTERM, which saves a checkpoint
// and exits 143, or SIGKILL, after which the last periodic checkpoint remains) continues with
// `physgrad resume` to the same losses, trained networks and final figures as a run that was
// never interrupted; a damaged checkpoint or config is a one-line error that changes nothing.
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdlib>
#include <tuple>
#include <nlohmann/json.hpp>

#include "cli_fixture.hpp"

namespace {

using physgrad::testing::Cli;
using physgrad::testing::interrupt_when;
using physgrad::testing::metrics_without_time;
using physgrad::testing::Outcome;
using physgrad::testing::read_file;
namespace fs = std::filesystem;

// Six runs (Adam, Gauss-Newton, HIG for λ = 1 and 0.01) of 1500 iterations each.
const std::string kRun =
    "run hig-toy --seeds 1 --iters 1500 --eval-every 100 --checkpoint-every 50 --out ";

// Final losses per run from summary.json.
nlohmann::json final_losses(const fs::path& folder) {
  nlohmann::json finals = nlohmann::json::array();
  const nlohmann::json summary = nlohmann::json::parse(read_file(folder / "summary.json"));
  for (const auto& run : summary.at("runs")) {
    finals.push_back({run["label"], run["final"], run["iterations"], run["termination"]});
  }
  return finals;
}

class Resume : public Cli {
 protected:
  // Starts the run into `folder`, waits until its checkpoint holds the third run in progress
  // and sends `signal`; returns the exit status.
  int interrupt(const std::string& folder, int signal) {
    return interrupt_when(spawn(kRun + folder), dir_ / folder / "checkpoint.pgc", "\"index\":2",
                          signal);
  }

  // Runs `command` into `folder` with a SIGKILL right after its checkpoint number `kill`.
  void kill_at_checkpoint(const std::string& command, const std::string& folder, int kill) {
    ASSERT_EQ(run(command + folder, "PHYSGRAD_FAULT=kill@checkpoint:" + std::to_string(kill))
                  .exit_code,
              128 + SIGKILL);
  }

  // The run in progress that the checkpoint of `folder` holds.
  nlohmann::json run_in_progress(const std::string& folder) {
    const std::string saved = read_file(dir_ / folder / "checkpoint.pgc");
    return nlohmann::json::parse(saved.substr(saved.find('\n') + 1))["current"];  // past the header
  }

  // `physgrad resume folder` ends with the metrics and networks of the uninterrupted run "whole".
  void expect_resumes_to_whole(const std::string& folder, int kill) {
    const Outcome resumed = run("resume " + folder);
    ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
    EXPECT_EQ(metrics_without_time(dir_ / folder), metrics_without_time(dir_ / "whole")) << kill;
    EXPECT_EQ(read_file(dir_ / folder / "networks.json"),
              read_file(dir_ / "whole" / "networks.json"))
        << kill;
  }
};

TEST_F(Resume, TerminatedRunContinuesToTheSameResults) {
  ASSERT_EQ(run(kRun + "whole").exit_code, 0);

  const int status = interrupt("part", SIGTERM);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM);
  const std::string err = read_file(configs_ / "spawned.err");
  EXPECT_NE(err.find("checkpoint kept, continue with: physgrad resume part"), std::string::npos)
      << err;
  // The interrupted folder holds the settings and the checkpoint, nothing half-written.
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir_ / "part")) {
    files.push_back(entry.path().filename().string());
  }
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files, (std::vector<std::string>{"checkpoint.pgc", "config.json"}));

  const Outcome resumed = run("resume part");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_FALSE(fs::exists(dir_ / "part" / "checkpoint.pgc"));
  EXPECT_EQ(metrics_without_time(dir_ / "part"), metrics_without_time(dir_ / "whole"));
  EXPECT_EQ(read_file(dir_ / "part" / "networks.json"), read_file(dir_ / "whole" / "networks.json"));
  EXPECT_EQ(final_losses(dir_ / "part"), final_losses(dir_ / "whole"));
  // Nothing else is left beside the two run folders.
  std::size_t entries = 0;
  for (const auto& entry : fs::directory_iterator(dir_)) entries += entry.is_directory();
  EXPECT_EQ(entries, 2u);
}

TEST_F(Resume, KilledRunContinuesFromItsLastPeriodicCheckpoint) {
  ASSERT_EQ(run(kRun + "whole").exit_code, 0);
  const int status = interrupt("part", SIGKILL);
  ASSERT_TRUE(WIFSIGNALED(status));
  const Outcome resumed = run("resume part");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_EQ(metrics_without_time(dir_ / "part"), metrics_without_time(dir_ / "whole"));
  EXPECT_EQ(read_file(dir_ / "part" / "networks.json"), read_file(dir_ / "whole" / "networks.json"));
  // The killed process's staging folder is gone too.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 2);
}

// A run Adam pretrains for 40 iterations before HIG takes over (--pretrain), killed just after
// its checkpoint in the Adam part, at the switch and in the HIG part (the 7th, 8th and 9th
// checkpoint: the HIG run before it writes five and its finished entry), continues to the
// metrics and networks of the uninterrupted run.
TEST_F(Resume, PretrainedRunContinuesFromItsAdamPartOrItsRulePart) {
  const std::string pretrained =
      "run hig-toy --seeds 1 --lambda 0.01 --optimizers hig --pretrain 40 --iters 100 "
      "--eval-every 10 --checkpoint-every 20 --out ";
  ASSERT_EQ(run(pretrained + "whole").exit_code, 0);
  for (const auto& [kill, iteration] : {std::pair{7, 20}, {8, 40}, {9, 60}}) {
    const std::string folder = "part" + std::to_string(kill);
    ASSERT_NO_FATAL_FAILURE(kill_at_checkpoint(pretrained, folder, kill));
    const nlohmann::json current = run_in_progress(folder);
    EXPECT_EQ(current["key"]["optimizer"], "adam-hig");
    EXPECT_EQ(current["state"]["summary"]["iterations"], iteration);
    ASSERT_NO_FATAL_FAILURE(expect_resumes_to_whole(folder, kill));
  }
}

// poisson on two paired seeds with its Adam→HIG twin and no control (three runs a seed, each
// checkpointed at iterations 4 and 8 and when it finishes): killed at the 13th checkpoint (the
// second seed's HIG run at iteration 4) and the 17th (its twin at 8), it continues to the metrics
// and networks of the uninterrupted run, both seeds' runs numbered as before.
TEST_F(Resume, SeveralSeedsOfAPretrainedExperimentContinue) {
  const std::string seeds =
      "run poisson --grid 4 --train-size 32 --test-size 8 --batch 8 --iters 10 --eval-every 2 "
      "--pretrain 4 --control off --seeds 2 --checkpoint-every 4 --out ";
  ASSERT_EQ(run(seeds + "whole").exit_code, 0);
  for (const auto& [kill, rule, iteration] :
       {std::tuple{13, "hig", 4}, std::tuple{17, "adam-hig", 8}}) {
    const std::string folder = "seeds" + std::to_string(kill);
    ASSERT_NO_FATAL_FAILURE(kill_at_checkpoint(seeds, folder, kill));
    const nlohmann::json current = run_in_progress(folder);
    EXPECT_EQ(current["key"]["seed"], 1) << kill;
    EXPECT_EQ(current["key"]["optimizer"], rule) << kill;
    EXPECT_EQ(current["state"]["summary"]["iterations"], iteration) << kill;
    ASSERT_NO_FATAL_FAILURE(expect_resumes_to_whole(folder, kill));
    EXPECT_EQ(final_losses(dir_ / folder), final_losses(dir_ / "whole")) << kill;
  }
}

// A U-net with batch norm on fresh batches (heat-inverse on 8×8 cells, 4 filters), killed at its
// 3rd and 5th checkpoint (Adam's run, then SIP's), continues to the metrics and networks of the
// uninterrupted run, bit for bit.
TEST_F(Resume, UNetRunContinuesBitIdentically) {
  const std::string unet =
      "run heat-inverse --n 8 --filters 4 --train-size 8 --test-size 4 --batch 4 --iters 12 "
      "--eval-every 3 --checkpoint-every 4 --optimizers adam,sip --out ";
  ASSERT_EQ(run(unet + "whole").exit_code, 0);
  for (const int kill : {3, 5}) {
    const std::string folder = "unet" + std::to_string(kill);
    ASSERT_NO_FATAL_FAILURE(kill_at_checkpoint(unet, folder, kill));
    ASSERT_NO_FATAL_FAILURE(expect_resumes_to_whole(folder, kill));
  }
}

TEST_F(Resume, DamagedCheckpointOrConfigIsOneLineAndChangesNothing) {
  ASSERT_TRUE(WIFEXITED(interrupt("part", SIGTERM)));
  const fs::path folder = dir_ / "part";
  const std::string checkpoint = read_file(folder / "checkpoint.pgc");
  const std::string config = read_file(folder / "config.json");
  ASSERT_GT(checkpoint.size(), 1000u);

  const auto expect_refused = [&](const std::string& args, const std::string& needle) {
    const Outcome outcome = run(args);
    EXPECT_EQ(outcome.exit_code, 2) << args;
    EXPECT_EQ(std::count(outcome.err.begin(), outcome.err.end(), '\n'), 1) << outcome.err;
    EXPECT_NE(outcome.err.find(needle), std::string::npos) << outcome.err;
  };
  const auto with_files = [&](const std::string& new_checkpoint, const std::string& new_config,
                              const std::string& needle) {
    std::ofstream(folder / "checkpoint.pgc", std::ios::binary) << new_checkpoint;
    std::ofstream(folder / "config.json", std::ios::binary) << new_config;
    expect_refused("resume part", needle);
    // The folder is as it was: the same two files, nothing staged beside it.
    EXPECT_EQ(read_file(folder / "checkpoint.pgc"), new_checkpoint);
    EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), 2);
    EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
  };
  with_files(checkpoint.substr(0, checkpoint.size() / 2), config, "truncated");
  std::string flipped = checkpoint;
  flipped[flipped.size() / 2] = flipped[flipped.size() / 2] == '1' ? '2' : '1';
  with_files(flipped, config, "checksum mismatch");
  with_files("not a checkpoint\n", config, "not a physgrad checkpoint");
  with_files(checkpoint + "x", config, "longer than");
  std::string other_lr = config;
  other_lr.replace(other_lr.find("\"lr\": null"), 10, "\"lr\": 0.5");
  with_files(checkpoint, other_lr, "disagree on --lr");
  with_files(checkpoint, "{\"experiment\": \"hig-toy\", \"settings\": {\"iters\": 0}}",
             "--iters");
  with_files(checkpoint, "{", "invalid JSON");
  // An interrupted folder is no place for a new run; a folder without a checkpoint is not one
  // to resume; the intact folder still resumes.
  std::ofstream(folder / "checkpoint.pgc", std::ios::binary) << checkpoint;
  std::ofstream(folder / "config.json", std::ios::binary) << config;
  expect_refused(kRun + "part", "physgrad resume part");
  expect_refused("resume no-such-folder", "'no-such-folder' does not exist");
  // Another BLAS thread count than the checkpoint's is allowed, with a warning.
  const char* threads = std::getenv("OPENBLAS_NUM_THREADS");
  const std::string saved_threads = threads == nullptr ? "" : threads;
  ::setenv("OPENBLAS_NUM_THREADS", saved_threads == "2" ? "3" : "2", 1);
  const Outcome resumed = run("resume part");
  if (saved_threads.empty()) {
    ::unsetenv("OPENBLAS_NUM_THREADS");
  } else {
    ::setenv("OPENBLAS_NUM_THREADS", saved_threads.c_str(), 1);
  }
  EXPECT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.err.find("physgrad: warning: the checkpoint was written with blas_threads"),
            std::string::npos)
      << resumed.err;
  EXPECT_TRUE(fs::exists(folder / "report.html"));
}

}  // namespace
