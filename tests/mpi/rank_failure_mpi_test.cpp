// Ranks that cannot work together end the job instead of waiting for ever: ranks started with
// different settings, or one with another command, stop at their start with one error line on
// every rank (exit code 2) and write nothing; a rank that stops answering (SIGSTOP) ends the job
// within the time limit PHYSGRAD_RANK_TIMEOUT plus a few seconds, rank 0 keeping a checkpoint
// that resumes; SIGTERM to mpiexec while a rank is stopped keeps one too.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>

#include "../cli_fixture.hpp"
#include "mpi_fixture.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The pid of rank `rank` among the processes mpiexec `launcher` started, or -1.
pid_t rank_pid(pid_t launcher, int rank) {
  const std::string wanted = "OMPI_COMM_WORLD_RANK=" + std::to_string(rank);
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(entry.path() / "stat");
    std::string line;
    std::getline(stat, line);
    const std::size_t close = line.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(line.substr(close + 2));
    char state = 0;
    pid_t parent = 0;
    rest >> state >> parent;
    if (parent != launcher) continue;
    std::ifstream variables(entry.path() / "environ");
    for (std::string variable; std::getline(variables, variable, '\0');) {
      if (variable == wanted) return static_cast<pid_t>(std::stol(name));
    }
  }
  return -1;
}

class MpiRanks : public physgrad::testing::MpiFixture {
 protected:
  void TearDown() override {
    fs::remove(err_file());
    MpiFixture::TearDown();
  }

  // `first` on rank 0 and `second` on rank 1 (each "PROGRAM ARGS"), at most 120 s; the exit
  // code, stderr in `err` and the seconds it took in `took`.
  int run_two(const std::string& first, const std::string& second, std::string& err,
              double& took) const {
    const std::string n = std::string(" ") + PHYSGRAD_MPIEXEC_NUMPROC_FLAG + " 1 ";
    const auto start = Clock::now();
    const int code = run_line(
        "timeout -k 10 120 sh -c \"" + launcher() + n + first + " :" + n + second + "\"", &err);
    took = seconds_since(start);
    return code;
  }

  // Starts `args` on 2 ranks with `env`, stderr into ERR_FILE; returns mpiexec's pid.
  pid_t spawn_two(const std::string& env, const std::string& args) const {
    const pid_t pid = ::fork();
    if (pid == 0) {
      const std::string line = launcher(env) + PHYSGRAD_MPIEXEC_NUMPROC_FLAG + " 2 '" +
                               PHYSGRAD_CLI + "' " + args + " > /dev/null 2> '" +
                               err_file().string() + "'";
      ::execl("/bin/sh", "sh", "-c", line.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    return pid;
  }
  fs::path err_file() const { return dir_.string() + "_spawned.err"; }

  // Waits for `pid` (at most `limit` seconds, then kills it and fails); its exit code.
  static int wait_for(pid_t pid, double limit) {
    const auto start = Clock::now();
    int status = 0;
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      if (seconds_since(start) > limit) {
        ADD_FAILURE() << "mpiexec still runs after " << limit << " s";
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        return -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

  // Polls `ready` for at most `limit` seconds.
  static void wait_until(const std::function<bool()>& ready, double limit = 120) {
    const auto start = Clock::now();
    while (!ready() && seconds_since(start) < limit) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  bool is_empty() const { return fs::is_empty(dir_); }
};

const std::string kCli = std::string("'") + PHYSGRAD_CLI + "'";
const std::string kRun = kCli + " run hig-toy --seeds 1 --iters 100 --out a";
const std::string kRunNoIters = kCli + " run hig-toy --seeds 1 --out a";

TEST_F(MpiRanks, RanksStartedWithDifferentSettingsStopAtTheirStart) {
  struct Case {
    std::string second, difference;
  };
  for (const Case& c :
       {Case{kRunNoIters + " --iters 300", "--iters is '100' on rank 0 but '300' on rank 1"},
        Case{kRun + " --optimizers gn,hig",
             "--optimizers is 'adam,gn,hig' on rank 0 but 'gn,hig' on rank 1"},
        Case{kCli + " run hig-toy --seeds 1 --iters 100 --out b",
             "--out is 'a' on rank 0 but 'b' on rank 1"},
        Case{kCli + " list", "the command is 'run hig-toy' on rank 0 but 'list' on rank 1"},
        Case{kCli + " run hig-toy --help",
             "the command is 'run hig-toy' on rank 0 but 'run hig-toy --help' on rank 1"}}) {
    std::string err;
    double took = 0;
    EXPECT_EQ(run_two(kRun, c.second, err, took), 2) << c.second << ": " << err;
    std::cout << c.second << ": ended in " << took << " s\n";
    EXPECT_LT(took, 60) << c.second;
    for (const char* rank : {"rank 0 of 2: ", "rank 1 of 2: "}) {
      EXPECT_NE(err.find(std::string("physgrad: error: ") + rank +
                         "the ranks were not started alike: " + c.difference +
                         "; start every rank with the same command and settings\n"),
                std::string::npos)
          << c.second << ": " << err;
    }
    EXPECT_TRUE(is_empty()) << c.second << ": something was written";
  }
}

// Rank 1 stopped: rank 0 notices within the limit, saves its checkpoint and ends the job; the
// run then resumes on 2 ranks to the end. Rank 0 stopped: rank 1 ends the job, after giving
// rank 0 its few seconds.
TEST_F(MpiRanks, ARankThatStopsAnsweringEndsTheJobWithinTheLimit) {
  const double limit = 3;
  const std::string env = "PHYSGRAD_RANK_TIMEOUT=3";
  const std::string args =
      "run hig-toy --seeds 1 --lambda 1 --iters 1500 --eval-every 500 --checkpoint-every 100 "
      "--out ";
  for (const int silent : {1, 0}) {
    const std::string out = "silent" + std::to_string(silent);
    const pid_t launcher = spawn_two(env, args + out);
    wait_until([&] { return fs::exists(dir_ / out / "checkpoint.pgc"); });
    const pid_t stopped = rank_pid(launcher, silent);
    ASSERT_GT(stopped, 0);
    ::kill(stopped, SIGSTOP);
    const auto start = Clock::now();
    const int code = wait_for(launcher, limit + 30);
    const double took = seconds_since(start);
    std::cout << "rank " << silent << " stopped: the job ended " << took << " s later\n";
    const std::string err = physgrad::testing::read_file(err_file());
    EXPECT_EQ(code, 2) << err;
    EXPECT_LT(took, limit + 10) << err;
    EXPECT_NE(err.find("physgrad: error: rank " + std::to_string(1 - silent) +
                       " of 2: no answer from rank " + std::to_string(silent) + " within 3 s"),
              std::string::npos)
        << err;
    if (silent == 1) {
      EXPECT_NE(err.find("checkpoint kept, continue with: physgrad resume " + out),
                std::string::npos)
          << err;
    }
    // mpiexec has killed it (it may take a moment to be gone).
    wait_until([&] { return ::kill(stopped, 0) != 0; }, 10);
    EXPECT_NE(::kill(stopped, 0), 0) << "the stopped rank outlived the job";
    ::kill(stopped, SIGKILL);
    ASSERT_TRUE(fs::exists(dir_ / out / "checkpoint.pgc"));
    std::string resumed;
    EXPECT_EQ(run(2, "resume " + out, &resumed), 0) << resumed;
    EXPECT_TRUE(physgrad::testing::is_finished(dir_ / out));
  }
}

// A rank stopped inside a large sum, after the barrier that opens it (blocking_watch_check.cpp):
// the watch of the blocking part ends the job within the limit.
TEST_F(MpiRanks, ARankStoppedInsideALargeSumEndsTheJobWithinTheLimit) {
  std::string err;
  const auto start = Clock::now();
  EXPECT_EQ(run(2, "2", &err, PHYSGRAD_BLOCKING_WATCH_CHECK), 2) << err;
  const double took = seconds_since(start);
  std::cout << "a rank stopped inside a large sum: the job ended after " << took << " s\n";
  EXPECT_LT(took, 2 + 10) << err;
  EXPECT_NE(err.find("physgrad: error: rank 0 of 2: a blocking exchange of 1048576 numbers from "
                     "this rank did not end within 2 s"),
            std::string::npos)
      << err;
}

// A rank stopped inside the distributed eigensolve, after the exchange that opens it: ScaLAPACK's
// own exchanges run under the same watch, so the job ends within the limit.
TEST_F(MpiRanks, ARankStoppedInsideTheDistributedEigensolveEndsTheJobWithinTheLimit) {
  std::string err;
  const auto start = Clock::now();
  const int code = run(2, "2 eigensolve", &err, PHYSGRAD_BLOCKING_WATCH_CHECK);
  if (code == 3) GTEST_SKIP() << "this build has no distributed eigensolver (ScaLAPACK)";
  EXPECT_EQ(code, 2) << err;
  const double took = seconds_since(start);
  std::cout << "a rank stopped inside the distributed eigensolve: the job ended after " << took
            << " s\n";
  EXPECT_LT(took, 2 + 10) << err;
  EXPECT_NE(err.find("physgrad: error: rank 0 of 2: a blocking exchange of"), std::string::npos)
      << err;
  EXPECT_NE(err.find("did not end within 2 s"), std::string::npos) << err;
}

// SIGTERM to mpiexec while rank 1 is stopped (before any periodic checkpoint is due): the ranks
// get SIGCONT and SIGTERM, stop at the same iteration, and rank 0 saves its checkpoint.
TEST_F(MpiRanks, SigtermToMpiexecWhileARankIsStoppedKeepsACheckpoint) {
  const pid_t launcher =
      spawn_two("PHYSGRAD_RANK_TIMEOUT=60", "run hig-toy --seeds 1 --iters 20000 --out t");
  wait_until([&] {
    return physgrad::testing::read_file(err_file()).find("iteration 0,") != std::string::npos;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const pid_t stopped = rank_pid(launcher, 1);
  ASSERT_GT(stopped, 0);
  ::kill(stopped, SIGSTOP);
  std::this_thread::sleep_for(std::chrono::seconds(1));
  ::kill(launcher, SIGTERM);
  wait_for(launcher, 30);
  const std::string err = physgrad::testing::read_file(err_file());
  EXPECT_NE(err.find("stopped on request"), std::string::npos) << err;
  EXPECT_TRUE(fs::exists(dir_ / "t" / "checkpoint.pgc")) << err;
  ::kill(stopped, SIGKILL);
}

TEST_F(MpiRanks, ABadTimeLimitIsRefusedBeforeTheRanksStart) {
  for (const std::string value : {"0", "-1", "5 ", "abc", "inf", "1e7"}) {
    std::string err;
    EXPECT_EQ(run_line(launcher("PHYSGRAD_RANK_TIMEOUT='" + value + "'") +
                           PHYSGRAD_MPIEXEC_NUMPROC_FLAG + " 2 " + kRun,
                       &err),
              2)
        << value << ": " << err;
    EXPECT_NE(err.find("physgrad: error: PHYSGRAD_RANK_TIMEOUT: '" + value +
                       "' is not a number of seconds in (0, 1e6]"),
              std::string::npos)
        << err;
  }
  EXPECT_TRUE(is_empty());
}

}  // namespace
