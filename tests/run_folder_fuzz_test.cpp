// A seeded random sequence of what users and accidents do to run folders — runs and resumes
// spelled with trailing slashes, "." and symbolic links; SIGKILL at the steps that matter and at
// random moments; SIGTERM; concurrent runs and resumes on one folder; a run of another
// experiment; a folder deleted by hand; a folder renamed away while its run is stopped at a step
// and a finished folder put at its path — checked after every operation: a finished result never
// changes, every folder is absent, empty, unfinished or finished, a process that finds no other
// one alive never says "in use", and nothing appears outside the folders. At the end every
// unfinished folder resumes, and every finished one holds exactly the results of an
// uninterrupted run. PHYSGRAD_FUZZ_SEED=N replays another sequence.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "cli_fixture.hpp"

namespace {

using physgrad::testing::Cli;
using physgrad::testing::is_finished;
using physgrad::testing::metrics_without_time;
using physgrad::testing::read_file;
using physgrad::testing::snapshot;
namespace fs = std::filesystem;

const std::string kLearning =
    "run hig-toy --seeds 1 --lambda 1 --iters 60 --eval-every 20 --checkpoint-every 10 --out ";
const std::string kDirect = "run comparison --out ";

enum class State { kAbsent, kEmpty, kUnfinished, kFinished, kForeign };

const char* name(State state) {
  switch (state) {
    case State::kAbsent: return "absent";
    case State::kEmpty: return "empty";
    case State::kUnfinished: return "unfinished";
    case State::kFinished: return "finished";
    case State::kForeign: return "foreign";
  }
  return "?";
}

// The state as a user sees it; scratch of a killed process (dot files) is allowed anywhere but
// in a finished folder.
State state_of(const fs::path& folder) {
  std::error_code error;
  if (!fs::exists(folder, error)) return State::kAbsent;
  if (!fs::is_directory(folder)) return State::kForeign;
  std::set<std::string> visible;
  bool scratch = false;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string file = entry.path().filename().string();
    if (file[0] == '.') {
      scratch = true;
    } else {
      visible.insert(file);
    }
  }
  const bool summary = visible.count("summary.json") > 0;
  const bool checkpoint = visible.count("checkpoint.pgc") > 0;
  if (summary && !checkpoint) return scratch || !is_finished(folder) ? State::kForeign : State::kFinished;
  if (visible.count("config.json") > 0) return State::kUnfinished;
  return visible.empty() ? State::kEmpty : State::kForeign;
}

class RunFolderFuzz : public Cli {
 protected:
  struct Exit {
    int code = 0;  // exit code, or 128 + signal
    std::string err;
  };

  Exit wait_for(pid_t pid, const std::string& tag) const {
    int status = 0;
    ::waitpid(pid, &status, 0);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status),
            read_file(configs_ / (tag + ".err"))};
  }

  std::string spelling(const std::string& folder) {
    std::vector<std::string> forms = {folder, folder + "/", (fs::path(".") / folder).string(),
                                      folder + "/.", folder + "//", (dir_ / folder).string() + "/"};
    if (folder == "b") forms.insert(forms.end(), {"lb", "lb/", "lb/."});
    return forms[pick(forms.size())];
  }
  std::size_t pick(std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_); }

  std::mt19937 rng_;
};

TEST_F(RunFolderFuzz, SeededOperationsNeverLoseAFinishedResultNorLeaveAnUnresumableFolder) {
  const char* seed_text = std::getenv("PHYSGRAD_FUZZ_SEED");
  const unsigned seed = seed_text == nullptr ? 20261124u : static_cast<unsigned>(std::atol(seed_text));
  rng_.seed(seed);
  SCOPED_TRACE("PHYSGRAD_FUZZ_SEED=" + std::to_string(seed));
  // The uninterrupted results, and how long each kind of run takes here: a signal at a random
  // moment comes within 1.2 times that, so that most land while the run is going on.
  const auto timed = [&](const std::string& args) {
    const auto begin = std::chrono::steady_clock::now();
    EXPECT_EQ(run(args).exit_code, 0) << args;
    const auto took = std::chrono::steady_clock::now() - begin;
    return 1 + static_cast<std::size_t>(
                   1.2 * std::chrono::duration<double, std::milli>(took).count());
  };
  const std::size_t learning_ms = timed(kLearning + "ref-learning");
  const std::size_t direct_ms = timed(kDirect + "ref-direct");
  ASSERT_FALSE(HasFailure());
  fs::create_directory_symlink("b", dir_ / "lb");  // dangling until b exists
  const std::vector<std::string> folders = {"a", "b", "n/c"};
  const std::set<std::string> top_level = {"ref-learning", "ref-direct", "a", "b", "n", "lb"};

  std::map<std::string, std::map<std::string, std::string>> finished;  // folder → its files
  std::map<std::string, int> seen;  // what the sequence reached, to show it covered the states
  constexpr int kRounds = 100;
  for (int round = 0; round < kRounds; ++round) {
    const std::string folder = folders[pick(folders.size())];
    // Resume where there is something to resume, mostly; start a run elsewhere, mostly.
    const bool unfinished = state_of(dir_ / folder) == State::kUnfinished;
    const auto resuming = [&] { return pick(6) < (unfinished ? 4u : 1u); };
    const bool first = round == 0;  // always a run killed at a checkpoint (below)
    const bool learning = first || pick(4) != 0;
    const std::string start = (learning ? kLearning : kDirect) + spelling(folder);
    const std::string resume = "resume " + spelling(folder);
    const std::vector<std::string> faults = {
        "", "kill@claimed:1", "kill@checkpoint:" + std::to_string(1 + pick(first ? 6 : 20)),
        "kill@commit:" + std::to_string(1 + pick(14))};
    std::vector<Exit> exits;
    bool concurrent = false;
    std::string op;
    // A finished folder is refused by everything but removal: remove it often, so that the
    // sequence keeps passing through the other states.
    const bool finished_now = state_of(dir_ / folder) == State::kFinished;
    // The first round is a run killed at one of its first checkpoints, so that every sequence
    // has an unfinished folder with a checkpoint to continue.
    switch (first ? 0 : finished_now && pick(2) == 0 ? 6 : pick(8)) {
      case 0: case 1: {  // a run or resume, perhaps killed at a step
        const bool resume_it = !first && resuming();
        const std::string fault = faults[first ? 2 : pick(faults.size())];
        op = (resume_it ? resume : start) + (fault.empty() ? "" : " [" + fault + "]");
        const auto outcome =
            run(resume_it ? resume : start, fault.empty() ? "" : "PHYSGRAD_FAULT=" + fault);
        exits.push_back({outcome.exit_code, outcome.err});
        break;
      }
      case 2: case 3: {  // killed or stopped at a random moment
        const int signal = pick(3) == 0 ? SIGTERM : SIGKILL;
        const bool resume_it = resuming();
        op = (resume_it ? resume : start) + " [signal " + std::to_string(signal) + "]";
        const pid_t pid = spawn(resume_it ? resume : start, "", "one");
        std::this_thread::sleep_for(std::chrono::milliseconds(pick(learning ? learning_ms : direct_ms)));
        ::kill(pid, signal);
        exits.push_back(wait_for(pid, "one"));
        break;
      }
      case 4: case 5: {  // two or three processes on one folder at once
        concurrent = true;
        const std::size_t n = 2 + pick(2);
        std::vector<pid_t> pids;
        const std::vector<std::string> tags = {"p0", "p1", "p2"};
        for (std::size_t i = 0; i < n; ++i) {
          const std::string args = resuming() ? resume : start;
          op += args + " & ";
          pids.push_back(spawn(args, "", tags[i]));
        }
        for (std::size_t i = 0; i < n; ++i) exits.push_back(wait_for(pids[i], tags[i]));
        break;
      }
      case 7: {  // stopped at a step, its folder renamed away and a finished one put at its path
        const bool resume_it = resuming();
        const std::string point = pick(3) == 0   ? "claimed:1"
                                  : pick(2) == 0 ? "checkpoint:" + std::to_string(1 + pick(20))
                                                 : "commit:" + std::to_string(1 + pick(14));
        const std::string reference = pick(2) == 0 ? "ref-learning" : "ref-direct";
        op = (resume_it ? resume : start) + " [stop@" + point + ", mv " + folder + " " + folder +
             ".moved, cp -r " + reference + " " + folder + "]";
        const pid_t pid = spawn(resume_it ? resume : start, "PHYSGRAD_FAULT=stop@" + point, "one");
        int status = 0;
        ::waitpid(pid, &status, WUNTRACED);
        if (!WIFSTOPPED(status)) {  // refused, or it ended before the point
          exits.push_back({WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status),
                           read_file(configs_ / "one.err")});
          break;
        }
        const fs::path moved = dir_ / (folder + ".moved");
        fs::rename(dir_ / folder, moved);
        fs::copy(dir_ / reference, dir_ / "copy", fs::copy_options::recursive);
        fs::rename(dir_ / "copy", dir_ / folder);
        finished[folder] = snapshot(dir_ / reference);  // checked below like any finished folder
        ::kill(pid, SIGCONT);
        exits.push_back(wait_for(pid, "one"));
        // The run went on in the folder it claimed: finished with the reference results, or
        // (failed) unfinished or empty; then the user removes it.
        const State moved_state = state_of(moved);
        EXPECT_NE(moved_state, State::kForeign);
        if (exits.back().code == 0) {
          EXPECT_EQ(moved_state, State::kFinished);
          const nlohmann::json config = nlohmann::json::parse(read_file(moved / "config.json"));
          EXPECT_EQ(metrics_without_time(moved),
                    metrics_without_time(dir_ / (config["experiment"] == "hig-toy"
                                                     ? "ref-learning"
                                                     : "ref-direct")));
        }
        seen["renamed and replaced mid-run"]++;
        fs::remove_all(moved);
        break;
      }
      default: {  // the user removes a folder by hand
        op = "rm -r " + folder;
        fs::remove_all(dir_ / folder);
        finished.erase(folder);
        break;
      }
    }
    SCOPED_TRACE("round " + std::to_string(round) + ": " + op);
    int successes = 0;
    for (const Exit& exit : exits) {
      EXPECT_TRUE(exit.code == 0 || exit.code == 2 || exit.code == 128 + SIGKILL ||
                  exit.code == 128 + SIGTERM)
          << exit.code << ": " << exit.err;
      successes += exit.code == 0;
      if (exit.code == 2) {
        const std::size_t at = exit.err.find("physgrad: error: ");
        ASSERT_NE(at, std::string::npos) << exit.err;
        const std::string line = exit.err.substr(at);
        EXPECT_EQ(std::count(line.begin(), line.end(), '\n'), 1) << line;
        if (!concurrent) {
          EXPECT_EQ(line.find("in use"), std::string::npos) << line;
        }
        seen[line.find("in use") != std::string::npos ? "refused: in use" : "refused"]++;
      }
    }
    EXPECT_LE(successes, 1) << "two processes finished one folder";
    if (std::getenv("PHYSGRAD_FUZZ_LOG") != nullptr) {
      std::cout << round << ": " << op << " →";
      for (const Exit& exit : exits) std::cout << ' ' << exit.code;
      std::cout << '\n';
      for (const Exit& exit : exits) {
        if (exit.code == 2) std::cout << "   " << exit.err.substr(exit.err.find("physgrad: error"));
      }
    }
    for (const std::string& f : folders) {
      const State state = state_of(dir_ / f);
      EXPECT_NE(state, State::kForeign) << f;
      seen[std::string(name(state)) +
           (state == State::kUnfinished && fs::exists(dir_ / f / "checkpoint.pgc") ? " (checkpoint)" : "")]++;
      if (finished.count(f) > 0) {
        EXPECT_EQ(state, State::kFinished) << f << " lost its finished result";
        EXPECT_TRUE(snapshot(dir_ / f) == finished[f]) << f << " changed after it was finished";
      } else if (state == State::kFinished) {
        finished[f] = snapshot(dir_ / f);
      }
    }
    for (const auto& entry : fs::directory_iterator(dir_)) {
      EXPECT_EQ(top_level.count(entry.path().filename().string()), 1u) << entry.path();
    }
    if (HasFailure()) break;
  }
  // Every unfinished folder resumes, and every finished one holds the uninterrupted results.
  for (const std::string& f : folders) {
    if (state_of(dir_ / f) == State::kUnfinished) {
      const auto resumed = run("resume " + f);
      EXPECT_EQ(resumed.exit_code, 0) << f << ": " << resumed.err;
    }
    if (state_of(dir_ / f) != State::kFinished) continue;
    const nlohmann::json config = nlohmann::json::parse(read_file(dir_ / f / "config.json"));
    const std::string reference = config["experiment"] == "hig-toy" ? "ref-learning" : "ref-direct";
    EXPECT_EQ(metrics_without_time(dir_ / f), metrics_without_time(dir_ / reference)) << f;
  }
  std::string coverage;
  for (const auto& [what, count] : seen) coverage += what + " " + std::to_string(count) + "; ";
  std::cout << "[ fuzz     ] seed " << seed << ": " << coverage << '\n';
  EXPECT_GT(seen["finished"], 0) << coverage;
  EXPECT_GT(seen["unfinished (checkpoint)"], 0) << coverage;
  EXPECT_GT(seen["refused"], 0) << coverage;
}

}  // namespace
