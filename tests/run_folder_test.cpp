// Run folders under attack: every spelling of a folder (trailing slashes, ".", symbolic links,
// mount points), concurrent runs on one folder, kills and failures at every step of a run. A
// finished result is never changed or lost, a second process on a live folder is refused, and
// a folder a run leaves behind either resumes to the results of an uninterrupted run or is gone.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/wait.h>

#include <cstring>
#include <map>

#include "cli_fixture.hpp"

namespace {

using physgrad::testing::Cli;
using physgrad::testing::metrics_without_time;
using physgrad::testing::Outcome;
using physgrad::testing::read_file;
using physgrad::testing::snapshot;
namespace fs = std::filesystem;

// Three learning runs (λ = 1) with evaluations and seven checkpoints each.
const std::string kLearning =
    "run hig-toy --seeds 1 --lambda 1 --iters 60 --eval-every 20 --checkpoint-every 10 --out ";

int one_line_count(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

// The error line of a failed run (learning runs print progress lines before it).
std::string error_line(const std::string& err) {
  const std::size_t at = err.find("physgrad: error: ");
  return at == std::string::npos ? std::string() : err.substr(at);
}

class RunFolderCli : public Cli {
 protected:
  // The uninterrupted learning run every interrupted one must reproduce.
  void make_reference() {
    const Outcome whole = run(kLearning + "whole");
    ASSERT_EQ(whole.exit_code, 0) << whole.err;
  }
  void expect_same_results(const std::string& folder) {
    EXPECT_EQ(metrics_without_time(dir_ / folder), metrics_without_time(dir_ / "whole")) << folder;
    EXPECT_EQ(read_file(dir_ / folder / "networks.json"), read_file(dir_ / "whole" / "networks.json"))
        << folder;
    EXPECT_TRUE(physgrad::testing::is_finished(dir_ / folder)) << folder;
  }
  Outcome swap_during(const std::string& args, const std::string& point, const std::string& folder,
                      const std::string& moved, const std::string& finished, int signal = 0);
  Outcome expect_refused(const std::string& args, const std::string& needle,
                         const std::string& subdir = "") {
    const Outcome outcome = run(args, "", subdir);
    EXPECT_EQ(outcome.exit_code, 2) << args << ": " << outcome.err;
    EXPECT_EQ(one_line_count(outcome.err), 1) << outcome.err;
    EXPECT_NE(outcome.err.find(needle), std::string::npos) << args << ": " << outcome.err;
    return outcome;
  }
};

TEST_F(RunFolderCli, EverySpellingOfAFinishedFolderLeavesItAsItIs) {
  ASSERT_EQ(run("run comparison --out r/").exit_code, 0);
  ASSERT_TRUE(fs::exists(dir_ / "r" / "summary.json"));
  const auto finished = snapshot(dir_ / "r");
  const std::string abs = (dir_ / "r").string();
  for (const std::string& out :
       std::vector<std::string>{"r", "r/", "r//", "./r", "r/.", "r/../r/", abs, abs + "/"}) {
    expect_refused("run comparison --out " + out, "holds the results of a finished run");
    expect_refused("resume " + out, "nothing to resume");
  }
  expect_refused("resume .", "nothing to resume", "r");
  // Nor does a run inside it add to it.
  for (const std::string& out : std::vector<std::string>{"r/sub", "r/a/b/", abs + "/sub"}) {
    expect_refused("run comparison --out " + out, "lies inside the run folder");
  }
  EXPECT_FALSE(fs::exists(dir_ / "r" / "sub") || fs::exists(dir_ / "r" / "a"));
  EXPECT_EQ(snapshot(dir_ / "r"), finished);
  // Nor inside an unfinished one that holds only its settings (killed at its claim), while a
  // config.json of something else further up does not count.
  EXPECT_NE(run("run comparison --out u", "PHYSGRAD_FAULT=kill@claimed:1").exit_code, 0);
  ASSERT_TRUE(fs::exists(dir_ / "u" / "config.json"));
  expect_refused("run comparison --out u/sub", "lies inside the run folder");
  fs::create_directory(dir_ / "other");
  std::ofstream(dir_ / "other" / "config.json") << "{\"a\": 1}";
  EXPECT_EQ(run("run comparison --iters 2 --out other/run").exit_code, 0);
  // An existing empty folder, named with a trailing slash, is used in place and kept.
  fs::create_directory(dir_ / "e");
  ASSERT_EQ(run("run comparison --out e/").exit_code, 0);
  EXPECT_TRUE(physgrad::testing::is_finished(dir_ / "e"));
  fs::create_directory(dir_ / "e2");
  const Outcome failed = run("run comparison --out e2/", "PHYSGRAD_FAULT=fail@claimed:1");
  EXPECT_EQ(failed.exit_code, 2);
  EXPECT_NE(failed.err.find("nothing was kept"), std::string::npos) << failed.err;
  EXPECT_TRUE(fs::is_directory(dir_ / "e2") && fs::is_empty(dir_ / "e2"));
}

TEST_F(RunFolderCli, AControlCharacterInAFolderNameIsRefused) {
  fs::create_directories(dir_ / ".victim");
  std::ofstream(dir_ / ".victim" / "keep.txt") << "keep";
  const std::string config = write_config("nul.json", "{\"out\": \"victim\\u0000\"}");
  const Outcome outcome = run("run comparison --config " + config);
  EXPECT_EQ(outcome.exit_code, 2);
  EXPECT_EQ(one_line_count(outcome.err), 1) << outcome.err;
  EXPECT_EQ(read_file(dir_ / ".victim" / "keep.txt"), "keep");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(RunFolderCli, ABlankFolderNameIsRefusedNotTakenForTheDefault) {
  // The shell words after --out, and the value they give.
  const std::vector<std::pair<std::string, std::string>> blanks = {
      {" ' '", " "}, {" '   '", "   "}, {" ''", ""}, {"=' '", " "}};
  for (const auto& [words, value] : blanks) {
    expect_refused("run comparison --iters 2 --out" + words,
                   "--out: '" + value + "' is blank; name a folder");
  }
  expect_refused("run comparison --config " + write_config("blank.json", "{\"out\": \"  \"}"),
                 "--out: '  ' is blank");
  expect_refused("resume ' '", "resume: ' ' is blank");
  EXPECT_TRUE(fs::is_empty(dir_));  // no runs/comparison-<timestamp> either
}

TEST_F(RunFolderCli, AnUnfinishedFolderWithAFileOfSomeoneElseIsNotResumed) {
  make_reference();
  ASSERT_EQ(run(kLearning + "u", "PHYSGRAD_FAULT=kill@checkpoint:3").exit_code, 128 + SIGKILL);
  for (const std::string foreign : {"notes.txt", "metrics.csv.bak", "sub"}) {
    if (foreign == "sub") {
      fs::create_directory(dir_ / "u" / foreign);
    } else {
      std::ofstream(dir_ / "u" / foreign) << "mine";
    }
    const auto before = snapshot(dir_ / "u");
    expect_refused("resume u", "resume: 'u' holds '" + foreign + "', which is no file of a run");
    EXPECT_EQ(snapshot(dir_ / "u"), before);
    EXPECT_TRUE(fs::exists(dir_ / "u" / foreign));
    fs::remove(dir_ / "u" / foreign);
  }
  // What a commit cut short moved in is the run's own: such a folder resumes (see
  // KilledAtAnyStepTheFolderResumesToTheSameResults); so does this one, once the file is gone.
  const Outcome resumed = run("resume u");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  expect_same_results("u");
}

TEST_F(RunFolderCli, ConcurrentRunsOnOneFolderLeaveOneResultAndNeverPointToResume) {
  std::vector<pid_t> pids;
  for (int i = 0; i < 3; ++i) {
    pids.push_back(spawn("run comparison --out same", "", "run" + std::to_string(i)));
  }
  int succeeded = 0;
  for (int i = 0; i < 3; ++i) {
    int status = 0;
    ::waitpid(pids[static_cast<std::size_t>(i)], &status, 0);
    ASSERT_TRUE(WIFEXITED(status));
    const std::string err = read_file(configs_ / ("run" + std::to_string(i) + ".err"));
    if (WEXITSTATUS(status) == 0) {
      ++succeeded;
      continue;
    }
    EXPECT_EQ(WEXITSTATUS(status), 2) << err;
    EXPECT_TRUE(err.find("in use by another physgrad process") != std::string::npos ||
                err.find("holds the results of a finished run") != std::string::npos)
        << err;
    EXPECT_EQ(err.find("resume"), std::string::npos) << err;
  }
  EXPECT_EQ(succeeded, 1);
  EXPECT_TRUE(physgrad::testing::is_finished(dir_ / "same"));
  // Without --out, runs started in the same second get a folder each.
  pids.clear();
  for (int i = 0; i < 3; ++i) pids.push_back(spawn("run comparison", "", "default" + std::to_string(i)));
  for (const pid_t pid : pids) {
    int status = 0;
    ::waitpid(pid, &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  }
  int folders = 0;
  for (const auto& entry : fs::directory_iterator(dir_ / "runs")) {
    folders += physgrad::testing::is_finished(entry.path());
  }
  EXPECT_EQ(folders, 3);
}

TEST_F(RunFolderCli, ALiveRunIsNeitherJoinedNorResumed) {
  const pid_t live = spawn(
      "run hig-toy --seeds 1 --lambda 1 --iters 100000 --checkpoint-every 100 --out live");
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!fs::exists(dir_ / "live" / "checkpoint.pgc") &&
         std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  for (const std::string& args : {kLearning + "live", std::string("resume live")}) {
    const Outcome refused = expect_refused(args, "in use by another physgrad process");
    EXPECT_EQ(refused.err.find("physgrad resume"), std::string::npos) << refused.err;
  }
  ::kill(live, SIGTERM);
  int status = 0;
  ::waitpid(live, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 128 + SIGTERM);
  // Now that it has stopped, the folder is an unfinished run: a new one is pointed to resume.
  expect_refused(kLearning + "live", "continue it with `physgrad resume live`");
}

TEST_F(RunFolderCli, KilledAtAnyStepTheFolderResumesToTheSameResults) {
  make_reference();
  const int results = static_cast<int>(
      std::distance(fs::directory_iterator(dir_ / "whole"), fs::directory_iterator()));
  // Killed after claiming (config.json only), at the first and a later checkpoint, and after
  // the first, a middle and the last result was moved in (summary.json, checkpoint still there).
  const std::vector<std::string> points = {
      "claimed:1", "checkpoint:1", "checkpoint:12", "commit:1", "commit:6",
      "commit:" + std::to_string(results)};
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string folder = "killed" + std::to_string(i);
    const Outcome killed = run(kLearning + folder, "PHYSGRAD_FAULT=kill@" + points[i]);
    EXPECT_EQ(killed.exit_code, 128 + SIGKILL) << points[i];
    expect_refused(kLearning + folder, "continue it with `physgrad resume " + folder + "`");
    const Outcome resumed = run("resume " + folder + "/");
    EXPECT_EQ(resumed.exit_code, 0) << points[i] << ": " << resumed.err;
    expect_same_results(folder);
  }
  // Killed while resuming, then resumed again.
  ASSERT_EQ(run(kLearning + "twice", "PHYSGRAD_FAULT=kill@checkpoint:4").exit_code, 137);
  ASSERT_EQ(run("resume twice", "PHYSGRAD_FAULT=kill@commit:2").exit_code, 137);
  ASSERT_EQ(run("resume .", "", "twice").exit_code, 0);
  expect_same_results("twice");
}

TEST_F(RunFolderCli, AFailedRunSaysWhatItKept) {
  make_reference();
  // A failure after checkpoints keeps them, in folders it made along the way.
  const Outcome failed = run(kLearning + "deep/new/f", "PHYSGRAD_FAULT=fail@checkpoint:9");
  EXPECT_EQ(failed.exit_code, 2);
  EXPECT_EQ(one_line_count(error_line(failed.err)), 1) << failed.err;
  EXPECT_NE(error_line(failed.err).find("checkpoint kept, continue with: physgrad resume deep/new/f"),
            std::string::npos)
      << failed.err;
  ASSERT_EQ(run("resume deep/new/f").exit_code, 0);
  expect_same_results("deep/new/f");
  // A failure before any checkpoint leaves nothing, not even the parents it created.
  const Outcome early = run(kLearning + "p/q/r", "PHYSGRAD_FAULT=fail@claimed:1");
  EXPECT_EQ(early.exit_code, 2);
  EXPECT_NE(early.err.find("nothing was kept"), std::string::npos) << early.err;
  EXPECT_FALSE(fs::exists(dir_ / "p"));
  const Outcome direct = run("run comparison --out d", "PHYSGRAD_FAULT=fail@commit:2");
  EXPECT_NE(direct.err.find("nothing was kept"), std::string::npos) << direct.err;
  EXPECT_FALSE(fs::exists(dir_ / "d"));
  // A resumed run that fails is kept for another try.
  ASSERT_EQ(run("run comparison --out c", "PHYSGRAD_FAULT=kill@claimed:1").exit_code, 137);
  const Outcome again = run("resume c", "PHYSGRAD_FAULT=fail@commit:3");
  EXPECT_NE(again.err.find("the folder is kept"), std::string::npos) << again.err;
  ASSERT_EQ(run("resume c").exit_code, 0);
  EXPECT_TRUE(physgrad::testing::is_finished(dir_ / "c"));
}

// Stops the run `args` at the fault point `point` (PHYSGRAD_FAULT=stop@POINT), renames its folder
// `folder` to `moved` and puts a copy of the finished folder `finished` at its path, lets the
// run go on (sending it `signal` first, unless 0) and returns its outcome.
Outcome RunFolderCli::swap_during(const std::string& args, const std::string& point,
                                  const std::string& folder, const std::string& moved,
                                  const std::string& finished, int signal) {
  const pid_t pid = spawn(args, "PHYSGRAD_FAULT=stop@" + point, "swapped");
  int status = 0;
  ::waitpid(pid, &status, WUNTRACED);
  EXPECT_TRUE(WIFSTOPPED(status)) << args << " did not stop at " << point;
  if (WIFSTOPPED(status)) {
    fs::rename(dir_ / folder, dir_ / moved);
    fs::copy(dir_ / finished, dir_ / "copy", fs::copy_options::recursive);
    fs::rename(dir_ / "copy", dir_ / folder);
    if (signal != 0) ::kill(pid, signal);  // delivered when it goes on
    ::kill(pid, SIGCONT);
    ::waitpid(pid, &status, 0);
  }
  return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status),
          read_file(configs_ / "swapped.out"), read_file(configs_ / "swapped.err")};
}

TEST_F(RunFolderCli, ARunRenamedAwayMidRunWritesIntoItsOwnFolderNeverIntoTheOneNowAtItsPath) {
  make_reference();
  ASSERT_EQ(run("run comparison --out victim").exit_code, 0);
  const auto victim = snapshot(dir_ / "victim");
  const int results = static_cast<int>(
      std::distance(fs::directory_iterator(dir_ / "whole"), fs::directory_iterator()));
  // Stopped after the claim (config.json only), between checkpoints, after the first result
  // was moved in, and after summary.json (the checkpoint still there).
  const std::vector<std::string> points = {"claimed:1", "checkpoint:5", "commit:1",
                                           "commit:" + std::to_string(results)};
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string folder = "run" + std::to_string(i);
    const Outcome outcome =
        swap_during(kLearning + folder, points[i], folder, folder + "-moved", "victim");
    EXPECT_EQ(outcome.exit_code, 0) << points[i] << ": " << outcome.err;
    EXPECT_EQ(snapshot(dir_ / folder), victim) << points[i] << ": the folder now at the path changed";
    expect_same_results(folder + "-moved");
    EXPECT_NE(outcome.out.find("report: " + (dir_ / (folder + "-moved") / "report.html").string()),
              std::string::npos)
        << outcome.out;
  }
  // A resumed run: stopped after it claimed the folder (before it read config.json and the
  // checkpoint), between checkpoints, and during its commit.
  const std::vector<std::string> resume_points = {"claimed:1", "checkpoint:3", "commit:2"};
  for (std::size_t i = 0; i < resume_points.size(); ++i) {
    const std::string folder = "resumed" + std::to_string(i);
    ASSERT_EQ(run(kLearning + folder, "PHYSGRAD_FAULT=kill@checkpoint:8").exit_code, 128 + SIGKILL);
    const Outcome outcome =
        swap_during("resume " + folder, resume_points[i], folder, folder + "-moved", "victim");
    EXPECT_EQ(outcome.exit_code, 0) << resume_points[i] << ": " << outcome.err;
    EXPECT_EQ(snapshot(dir_ / folder), victim) << resume_points[i];
    expect_same_results(folder + "-moved");
  }
  // A run stopped by SIGTERM after the swap: a direct run takes back its config.json from its
  // own folder (which stays, empty: the folder at its path is not the one it made); a learning
  // run leaves its checkpoint there, and that folder resumes.
  const Outcome direct =
      swap_during("run comparison --out d", "claimed:1", "d", "d-moved", "victim", SIGTERM);
  EXPECT_EQ(direct.exit_code, 128 + SIGTERM) << direct.err;
  EXPECT_NE(direct.err.find("nothing was kept"), std::string::npos) << direct.err;
  EXPECT_EQ(snapshot(dir_ / "d"), victim);
  EXPECT_TRUE(fs::is_directory(dir_ / "d-moved") && fs::is_empty(dir_ / "d-moved"));
  const Outcome learning =
      swap_during(kLearning + "l", "checkpoint:5", "l", "l-moved", "victim", SIGTERM);
  EXPECT_EQ(learning.exit_code, 128 + SIGTERM) << learning.err;
  EXPECT_NE(learning.err.find("continue with: physgrad resume " + (dir_ / "l-moved").string()),
            std::string::npos)
      << learning.err;
  EXPECT_EQ(snapshot(dir_ / "l"), victim);
  ASSERT_TRUE(fs::exists(dir_ / "l-moved" / "checkpoint.pgc"));
  ASSERT_EQ(run("resume l-moved").exit_code, 0);
  expect_same_results("l-moved");
}

TEST_F(RunFolderCli, ACommitThatFailsAfterARenameNamesTheFolderWhereItIsNow) {
  // Stopped after config.json was moved in; renamed; a folder put in the way of loss.svg.
  const pid_t pid = spawn("run comparison --out d", "PHYSGRAD_FAULT=stop@commit:1", "failed");
  int status = 0;
  ::waitpid(pid, &status, WUNTRACED);
  ASSERT_TRUE(WIFSTOPPED(status));
  fs::rename(dir_ / "d", dir_ / "d-moved");
  fs::create_directories(dir_ / "d-moved" / "loss.svg" / "in-the-way");
  ::kill(pid, SIGCONT);
  ::waitpid(pid, &status, 0);
  const std::string err = error_line(read_file(configs_ / "failed.err"));
  EXPECT_EQ(WEXITSTATUS(status), 2) << err;
  EXPECT_EQ(err.rfind("physgrad: error: '" + (dir_ / "d-moved").string() +
                          "': cannot move loss.svg into place: ",
                      0),
            0u)
      << err;
}

TEST_F(RunFolderCli, SymbolicLinksAreFollowedOrRefusedBeforeAnythingIsWritten) {
  fs::create_directory(dir_ / "target");
  fs::create_directory_symlink("target", dir_ / "link");
  ASSERT_EQ(run("run comparison --out link/").exit_code, 0);
  EXPECT_TRUE(fs::is_symlink(dir_ / "link"));
  EXPECT_TRUE(physgrad::testing::is_finished(dir_ / "target"));
  fs::create_directory(dir_ / "real");
  fs::create_directory_symlink("real", dir_ / "parent");
  ASSERT_EQ(run("run comparison --out parent/x").exit_code, 0);
  EXPECT_TRUE(physgrad::testing::is_finished(dir_ / "real" / "x"));

  fs::create_directory_symlink("nowhere", dir_ / "dangling");
  expect_refused("run comparison --out dangling", "which does not exist");
  expect_refused("resume dangling/", "which does not exist");
  expect_refused("run comparison --out dangling/.", "which does not exist");
  fs::create_directory_symlink("loop-b", dir_ / "loop-a");
  fs::create_directory_symlink("loop-a", dir_ / "loop-b");
  expect_refused("run comparison --out loop-a/x", "symbolic links");
  std::ofstream(dir_ / "file") << "a file";
  expect_refused("run comparison --out file", "not a directory");
  EXPECT_FALSE(fs::exists(dir_ / "nowhere"));
  EXPECT_EQ(read_file(dir_ / "file"), "a file");
}

TEST_F(RunFolderCli, AMountPointIsARunFolderLikeAnyOther) {
  fs::create_directory(dir_ / "mounted");
  if (::mount("tmpfs", (dir_ / "mounted").c_str(), "tmpfs", 0, "size=16m") != 0) {
    GTEST_SKIP() << "cannot mount a tmpfs here (needs root): " << std::strerror(errno);
  }
  const Outcome outcome = run("run comparison --out mounted/");
  const Outcome again = run("run comparison --out mounted");
  const bool finished = physgrad::testing::is_finished(dir_ / "mounted");
  ::umount((dir_ / "mounted").c_str());
  EXPECT_EQ(outcome.exit_code, 0) << outcome.err;
  EXPECT_EQ(again.exit_code, 2);
  EXPECT_TRUE(finished);
}

}  // namespace
