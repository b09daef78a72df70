// The command line under stop signals: a stop request ends a long simulation at its next time
// step and a long training step by dropping it (the state before it saved); a process busy where
// it never looks for stop requests ends after a grace period; a run interrupted at the second
// sweep of sin-rotation resumes to the results of an uninterrupted one.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <thread>

#include "hostile_fixture.hpp"
#include "physgrad/run/life/interrupt.hpp"

namespace {

using physgrad::testing::Hostile;
using physgrad::testing::interrupt_when;
using physgrad::testing::metrics_without_time;
using physgrad::testing::Outcome;
using physgrad::testing::read_file;
namespace fs = std::filesystem;

// A stop request during one long simulation ends it at the simulator's next time step: the
// first forward pass of a chain of 10⁷ steps takes seconds, the process ends within a second of
// SIGTERM, at a stop point (not killed after the grace period), and keeps nothing.
TEST_F(Hostile, AStopSignalEndsALongSimulationAtItsNextTimeStep) {
  const pid_t pid = spawn(
      "run time-reversal --problems fpu --fpu-steps 10000000 --optimizers pg --pg-inverse "
      "time_reversal --out long");
  const auto [status, seconds] = terminate_after_half_a_second(pid);
  ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM);
  EXPECT_LT(seconds, 1.0);
  const std::string err = read_file(configs_ / "spawned.err");
  EXPECT_NE(err.find("physgrad: fpu_chain: stopped on request; nothing was kept"),
            std::string::npos)
      << err;
  EXPECT_FALSE(fs::exists(dir_ / "long"));
}

// In a learning run the stop inside a step drops that step and saves the state before it.
TEST_F(Hostile, AStopSignalInsideALongTrainingStepSavesTheStateBeforeIt) {
  const std::string args =
      "run quantum-dipole --optimizers adam --train-size 16 --test-size 8 --batch 16 --steps "
      "20000 --iters 5 --eval-every 100 --checkpoint-every 1 --out part";
  const pid_t pid = spawn(args);
  // The checkpoint after step 1 is written just before step 2 (about 0.7 s) begins.
  const int status =
      interrupt_when(pid, dir_ / "part" / "checkpoint.pgc", "\"iterations\":1", SIGTERM);
  ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM);
  const std::string err = read_file(configs_ / "spawned.err");
  EXPECT_NE(err.find("stopped on request during iteration 2 (not applied); checkpoint kept"),
            std::string::npos)
      << err;
  EXPECT_NE(read_file(dir_ / "part" / "checkpoint.pgc").find("\"iterations\":1"),
            std::string::npos);
}


// A stop signal while the process is busy where it never looks for stop requests (here: making
// a large training set) ends it after the grace period, killed by that signal.
TEST_F(Hostile, AStopSignalEndsAProcessThatNeverReachesAStopPoint) {
  ::setenv("PHYSGRAD_STOP_GRACE", "1", 1);
  const pid_t pid = spawn("run poisson --train-size 200000 --iters 1 --out busy");
  ::unsetenv("PHYSGRAD_STOP_GRACE");
  const auto [status, seconds] = terminate_after_half_a_second(pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << status;
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_GE(seconds, 0.9);
  EXPECT_LT(seconds, 10.0);
  const std::string err = read_file(configs_ / "spawned.err");
  EXPECT_NE(err.find("physgrad: SIGTERM: no stop point reached within 1 s"), std::string::npos)
      << err;
  // Ended like a SIGKILL at its claim: the folder holds its settings and no result, which
  // `physgrad resume busy` runs from the start (RunFolderCli.KilledAtAnyStep… resumes such a
  // folder).
  EXPECT_TRUE(fs::exists(dir_ / "busy" / "config.json"));
  EXPECT_FALSE(fs::exists(dir_ / "busy" / "summary.json"));
  EXPECT_NE(err.find("physgrad resume goes on from there"), std::string::npos) << err;
}

using InterruptDeathTest = ::testing::Test;

TEST_F(InterruptDeathTest, AProcessBlockedAfterAStopRequestEndsAfterTheGracePeriod) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        physgrad::run::install_interrupt_handlers(0.2);
        ::raise(SIGINT);
        for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
      },
      ::testing::KilledBySignal(SIGINT), "SIGINT: no stop point reached within 0.2 s");
}

TEST_F(InterruptDeathTest, ARunThatReachesAStopPointEndsInItsOwnTime) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        physgrad::run::install_interrupt_handlers(0.2);
        ::raise(SIGTERM);
        if (!physgrad::run::stop_flag().load()) std::_Exit(1);
        physgrad::run::stop_point_reached();
        std::this_thread::sleep_for(std::chrono::milliseconds(600));  // saving, past the grace
        std::_Exit(physgrad::run::received_signal() == SIGTERM ? 7 : 1);
      },
      ::testing::ExitedWithCode(7), "");
}

// sin-rotation makes one sweep per ξ; its runs are numbered through the whole experiment, so a
// run interrupted at the second ξ resumes to the results of an uninterrupted one.
TEST_F(Hostile, SinRotationInterruptedAtTheSecondXiResumesToTheSameResults) {
  const std::string sin =
      "run sin-rotation --optimizers adam,sip --train-size 64 --test-size 16 --iters 400 "
      "--eval-every 100 --checkpoint-every 200 --out ";
  ASSERT_EQ(run(sin + "whole").exit_code, 0);
  const int status = interrupt_when(spawn(sin + "part"), dir_ / "part" / "checkpoint.pgc",
                                    "\"tag\":\"ξ=32\"", SIGTERM);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 128 + SIGTERM) << status;
  const Outcome resumed = run("resume part");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_EQ(metrics_without_time(dir_ / "part"), metrics_without_time(dir_ / "whole"));
  EXPECT_EQ(read_file(dir_ / "part" / "networks.json"), read_file(dir_ / "whole" / "networks.json"));
}

}  // namespace
