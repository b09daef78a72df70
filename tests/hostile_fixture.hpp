// The fixture of the hostile-input and stop-signal tests of the command line: a command refused
// (exit 2, one line naming the value, nothing written, nothing blocked), and a run interrupted.
#pragma once

#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <thread>
#include <utility>

#include "cli_fixture.hpp"

namespace physgrad::testing {

// hig-toy small enough to interrupt within a second: run 0 (Adam) finishes, run 1 (Gauss-Newton)
// is in progress when the checkpoint holds "index":1.
inline const std::string kHigToy =
    "run hig-toy --lambda 1 --seeds 1 --train-size 64 --test-size 16 --iters 1000 "
    "--eval-every 50 --checkpoint-every 100 --out ";

class Hostile : public Cli {
 protected:
  // Exit 2 and one stderr line containing `needle`; nothing new in the working folder.
  void expect_refused(const std::string& args, const std::string& needle) const {
    const std::size_t before = entries();
    const Outcome outcome = run(args);
    EXPECT_EQ(outcome.exit_code, 2) << args;
    EXPECT_EQ(std::count(outcome.err.begin(), outcome.err.end(), '\n'), 1)
        << args << ": " << outcome.err;
    EXPECT_NE(outcome.err.find(needle), std::string::npos) << args << ": " << outcome.err;
    EXPECT_EQ(entries(), before) << args << " left files behind";
  }

  // As expect_refused, for a command that must also not block: it is killed after 30 s. `shell`
  // runs before it in the same shell (a ulimit, say).
  void expect_refused_promptly(const std::string& args, const std::string& needle,
                               const std::string& shell = "") const {
    const pid_t pid = spawn_after(shell, args);
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    int status = 0;
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > give_up) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        FAIL() << args << " blocked";
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_TRUE(WIFEXITED(status)) << args;
    EXPECT_EQ(WEXITSTATUS(status), 2) << args;
    const std::string err = read_file(configs_ / "spawned.err");
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << args << ": " << err;
    EXPECT_NE(err.find(needle), std::string::npos) << args << ": " << err;
  }

  // spawn() with `shell` run first in the same shell.
  pid_t spawn_after(const std::string& shell, const std::string& args) const {
    if (shell.empty()) return spawn(args);
    const std::string command = shell + " && cd '" + dir_.string() + "' && exec '" +
                                PHYSGRAD_CLI + "' " + args + " > '" +
                                (configs_ / "spawned.out").string() + "' 2> '" +
                                (configs_ / "spawned.err").string() + "'";
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    return pid;
  }

  // Sends SIGTERM to `pid` half a second after it started and waits for it: its exit status
  // and the seconds from the signal to its end.
  static std::pair<int, double> terminate_after_half_a_second(pid_t pid) {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    const auto signalled = std::chrono::steady_clock::now();
    ::kill(pid, SIGTERM);
    int status = 0;
    ::waitpid(pid, &status, 0);
    return {status,
            std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count()};
  }

  std::size_t entries() const {
    return static_cast<std::size_t>(
        std::distance(fs::directory_iterator(dir_), fs::directory_iterator()));
  }

  // An interrupted hig-toy run in dir_/folder: run 0 finished, run 1 in progress.
  void interrupted(const std::string& folder) const {
    const int status = interrupt_when(spawn(kHigToy + folder), dir_ / folder / "checkpoint.pgc",
                                      "\"index\":1", SIGTERM);
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 128 + SIGTERM) << status;
  }
};

}  // namespace physgrad::testing
