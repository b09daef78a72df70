// The command line against hostile input: control characters and bytes that are not UTF-8 in
// any text value, files that are not plain files or are too large, crafted checkpoints (deep
// nesting, missing or null values), sizes beyond memory, list values that collide as labels,
// starts without a finite loss, unknown subcommands. Each is one line on stderr naming the value,
// exit code 2, nothing written and nothing blocked. A stop signal ends even a process that is
// busy where it never looks for stop requests, after a grace period.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <thread>

#include "cli_fixture.hpp"
#include "physgrad/run/interrupt.hpp"
#include "physgrad/io/checkpoint_file.hpp"

namespace {

using physgrad::testing::Cli;
using physgrad::testing::interrupt_when;
using physgrad::testing::metrics_without_time;
using physgrad::testing::Outcome;
using physgrad::testing::read_file;
namespace fs = std::filesystem;

// hig-toy small enough to interrupt within a second: run 0 (Adam) finishes, run 1 (Gauss-Newton)
// is in progress when the checkpoint holds "index":1.
const std::string kHigToy =
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

// A shell word that printf turns into the bytes of `escaped` (octal escapes like \001).
std::string bytes(const std::string& escaped) { return "\"$(printf '" + escaped + "')\""; }

TEST_F(Hostile, ControlCharactersAndBytesThatAreNotUtf8AreRefusedInEveryTextValue) {
  expect_refused("run comparison --iters 2 --out " + bytes("a\\001b"),
                 "--out: 'a\\x01b' contains the control character 0x01 at byte 1");
  expect_refused("run comparison --iters 2 --out=" + bytes("a\\nb"),
                 "--out: 'a\\x0ab' contains the control character 0x0a at byte 1");
  expect_refused("run comparison --iters 2 --out " + bytes("a\\377b"),
                 "is not valid UTF-8 (byte 0xff at 1)");
  expect_refused("run comparison --iters 2 --out " + bytes("a\\302\\205b"),
                 "contains the control character U+0085 at byte 1");
  expect_refused("run comparison --iters 2 --out r --pg-inverse " + bytes("gn\\tlbfgs"),
                 "--pg-inverse: 'gn\\x09lbfgs' contains the control character 0x09 at byte 2");
  expect_refused("resume " + bytes("r\\001"), "argument 2: 'r\\x01' contains the control");
  // In an option's name, the whole argument is named.
  expect_refused("run comparison " + bytes("\\055-o\\001ut=abc"),  // \055: '-' (printf)
                 "argument 3: '--o\\x01ut=abc' contains the control character 0x01 at byte 3");
  expect_refused("bench " + bytes("hig-toy\\033"), "'hig-toy\\x1b' contains the control");
  // Config files: a NUL in "out" once led to another folder; nothing is touched now.
  fs::create_directories(dir_ / ".victim");
  std::ofstream(dir_ / ".victim" / "keep") << "kept";
  for (const auto& [text, needle] : std::vector<std::pair<std::string, std::string>>{
           {R"({"out": "victim\u0000"})",
            "--out: 'victim\\x00' contains the control character 0x00 at byte 6"},
           {R"({"pg-inverse": ["gn\u0007"]})", "--pg-inverse: 'gn\\x07' contains the control"},
           {R"({"out": "a\u009bb"})", "--out: 'a"}}) {
    expect_refused("run comparison --config " + write_config("c.json", text), needle);
  }
  EXPECT_EQ(read_file(dir_ / ".victim" / "keep"), "kept");
}

TEST_F(Hostile, UnknownOrMissingSubcommandsAreNamed) {
  expect_refused("frobnicate",
                 "unknown subcommand 'frobnicate' (known: list, describe, run, resume, rules, "
                 "bench, report)");
  expect_refused("",
                 "a subcommand is required (known: list, describe, run, resume, rules, bench, "
                 "report)");
}

TEST_F(Hostile, FilesThatAreNotPlainOrTooLargeAreRefusedWithoutBlocking) {
  ASSERT_EQ(::mkfifo((configs_ / "fifo.json").c_str(), 0600), 0);
  expect_refused_promptly("run comparison --config " + (configs_ / "fifo.json").string(),
                          "fifo.json': is not a regular file (a FIFO)");
  expect_refused("run comparison --config /dev/zero",
                 "config file '/dev/zero': is not a regular file (a character device)");
  const std::string large = write_config("large.json", "{\"lr\": 0.1" +
                                                           std::string(2 << 20, ' ') + "}");
  expect_refused("run comparison --config " + large, "is 2097163 bytes, more than the 1048576 allowed");

  // The files of a folder to resume: a FIFO as the checkpoint or as config.json.
  interrupted("part");
  const fs::path folder = dir_ / "part";
  fs::rename(folder / "checkpoint.pgc", configs_ / "saved.pgc");
  ASSERT_EQ(::mkfifo((folder / "checkpoint.pgc").c_str(), 0600), 0);
  expect_refused_promptly("resume part", "checkpoint.pgc': is not a regular file (a FIFO)");
  fs::remove(folder / "checkpoint.pgc");
  fs::rename(configs_ / "saved.pgc", folder / "checkpoint.pgc");
  fs::rename(folder / "config.json", configs_ / "config.json");
  ASSERT_EQ(::mkfifo((folder / "config.json").c_str(), 0600), 0);
  expect_refused_promptly("resume part", "config.json': is not a regular file (a FIFO)");
}

// OpenBLAS retries a failed allocation of its 128 MiB work buffer for ever; under an address-space
// limit without room for it the command says so at once instead.
TEST_F(Hostile, AnAddressSpaceTooSmallForTheBlasBufferIsRefusedAtOnce) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space at start: no process of "
                  "this build runs under ulimit -v (the Release build runs this test)";
#endif
  for (const std::string& args : {std::string("run hig-toy --seeds 1 --iters 5 --out small"),
                                  std::string("bench hig-toy --steps 1")}) {
    expect_refused_promptly(args,
                            "the BLAS library's 128 MiB work buffer with 32 MiB to spare needs "
                            "160 MiB, more than the ",
                            "ulimit -v 200000");
  }
  EXPECT_EQ(entries(), 0u);
}

// Checkpoints with a valid checksum whose content this build did not write.
TEST_F(Hostile, CraftedCheckpointsAreRefusedAndTheIntactOneResumes) {
  interrupted("part");
  const fs::path path = dir_ / "part" / "checkpoint.pgc";
  const std::string original = read_file(path);
  const nlohmann::json document = physgrad::read_checkpoint_file(path);
  ASSERT_EQ(document["finished"].size(), 1u);
  const auto with_body = [&](const std::string& body, const std::string& needle) {
    char checksum[17];
    std::snprintf(checksum, sizeof checksum, "%016llx",
                  static_cast<unsigned long long>(physgrad::fnv1a64(body)));
    std::ofstream(path, std::ios::binary)
        << "physgrad-checkpoint 1 " << body.size() << " " << checksum << "\n" << body;
    expect_refused("resume part", needle);
  };
  const auto with = [&](const std::function<void(nlohmann::json&)>& change,
                        const std::string& needle) {
    nlohmann::json crafted = document;
    change(crafted);
    physgrad::write_checkpoint_file(path, crafted);
    expect_refused("resume part", needle);
  };
  with_body("{\"experiment\":\"hig-toy\",\"x\":" + std::string(300000, '[') +
                std::string(300000, ']') + "}",
            "JSON nested deeper than 64 levels");
  with_body("{\"experiment\":\"hig-toy\",\"experiment\":\"hig-toy\"}",
            "key 'experiment' appears twice");
  with_body("{\"experiment\":1e999}", "invalid JSON at line 1, column 19: number overflow");
  with([](nlohmann::json& d) { d["finished"][0]["summary"]["history"].back()["test_loss"] = nullptr; },
       "checkpoint: run 0 (adam, λ=1, seed 0): the record of iteration 1000 has no finite test "
       "loss");
  with([](nlohmann::json& d) { d["finished"][0]["summary"]["history"][0]["extras"].erase("y1"); },
       "the record of iteration 0 has no finite 'y1'");
  with([](nlohmann::json& d) { d["finished"][0]["summary"]["history"][1]["extras"]["y2"] = "x"; },
       "has no finite 'y2'");
  with([](nlohmann::json& d) { d["current"]["state"]["summary"]["history"][0]["extras"]["z"] = 1; },
       "run 1 (gn, λ=1, seed 0): the record of iteration 0 has values this experiment does not "
       "record");
  with([](nlohmann::json& d) { d["current"]["state"]["summary"]["history"][0]["test_loss"] = nullptr; },
       "run 1 (gn, λ=1, seed 0): the record of iteration 0 has no finite test loss");
  with([](nlohmann::json& d) { d["current"]["state"]["summary"]["iterations"] = 5000; },
       "run 1 (gn, λ=1, seed 0) has 5000 iterations, more than the run's 1000");
  with([](nlohmann::json& d) { d["current"]["state"]["epoch"] = 123456789; },
       "run 1 (gn, λ=1, seed 0): cannot resume training from this state: epoch 123456789 and "
       "batch start 0 do not follow from its ");
  // Nothing was changed by the refusals: the intact checkpoint resumes to a complete result.
  std::ofstream(path, std::ios::binary) << original;
  const Outcome resumed = run("resume part");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_EQ(read_file(dir_ / "part" / "metrics.csv").find("nan"), std::string::npos);
}

TEST_F(Hostile, SizesBeyondMemoryOrRangeAreRefusedNamingTheValue) {
  expect_refused("run hig-toy --train-size 1000000000000000",
                 "--train-size: 1000000000000000 (items of at least ");
  expect_refused("run sin-rotation --test-size 999999999999999", "--test-size: 999999999999999");
  expect_refused("run heat-inverse --n 1000000", "--n: 1000000 cells (a network of ~8·1000000²");
  expect_refused("run quantum-dipole --steps 1000000000", "--steps: must be in [1, 100000]");
  expect_refused("run comparison --iters 1000000000",
                 "--iters: 1000000000 (6 runs keeping every iterate) needs ");
  expect_refused("bench hig-toy --batch 100000",
                 "--batch: 100000 (the reference eigendecomposition of a 200000 × 200000 matrix) "
                 "needs ");
  expect_refused("bench hig-toy --warmup 9223372036854775807",
                 "--warmup: must be in [0, 1000000], got '9223372036854775807'");
  expect_refused("bench hig-toy --steps 9223372036854775807", "--steps: must be in [1, 1000000]");
}

// Every size of time-reversal is checked before anything runs: against its range, the work of
// one simulator pass, and the memory its runs keep.
TEST_F(Hostile, TimeReversalSizesBeyondTimeOrMemoryAreRefusedAtOnce) {
  expect_refused_promptly("run time-reversal --iters 1000000000",
                          "--iters: 1000000000 (12 runs keeping every iterate) needs ");
  expect_refused_promptly("run time-reversal --masses 100000000",
                          "--masses 100000000 × --fpu-steps 100: 1e+10 mass-steps per simulator "
                          "pass, more than the 1e+09");
  expect_refused_promptly("run time-reversal --masses 1152921504606846976",
                          "--masses: must be in [1, 1000000000], got '1152921504606846976'");
  expect_refused_promptly("run time-reversal --fpu-steps 9223372036854775807",
                          "--fpu-steps: must be in [1, 10000000], got '9223372036854775807'");
  expect_refused_promptly("run time-reversal --osc-steps 2000000",
                          "--osc-steps: must be in [1, 1000000]");
  // Gauss-Newton's Jacobian of a 10⁵-mass chain keeps 2·10⁵ trajectories; PG through the time
  // reversal alone needs one.
  expect_refused_promptly("run time-reversal --masses 100000",
                          "--masses: 100000 (items of at least ");
  expect_refused_promptly("run time-reversal --problems fpu --masses 1000 --fpu-steps 1000000",
                          "--masses: 1000 (items of at least 14.9 GiB each) needs 14.5 TiB");
  const Outcome alone = run(
      "run time-reversal --problems fpu --masses 100000 --optimizers pg --pg-inverse "
      "time_reversal --iters 1 --out alone");
  EXPECT_EQ(alone.exit_code, 0) << alone.err;
}

// The learning experiments check a given --batch against the memory and the work of a
// Gauss-Newton or HIG step, and --eval-every against the evaluations the limits allow.
TEST_F(Hostile, LearningStepsAndEvaluationsBeyondTimeOrMemoryAreRefused) {
  expect_refused_promptly("run heat-inverse --optimizers hig --batch 4096",
                          "--batch: 4096 (a gn or hig step forms a 33088² matrix from 262144 "
                          "Jacobian rows of 33088 weights) needs ");
  expect_refused_promptly("run heat-inverse --optimizers adam,gn --batch 256",
                          "--batch: 256 (a gn or hig step forms a 16384² matrix from 16384 "
                          "Jacobian rows of 33088 weights) takes 4.571e+12 multiply-adds, more "
                          "than the 1e+12");
  expect_refused_promptly("run hig-toy --iters 1000000000 --eval-every 1",
                          "--eval-every: 1 (1e+09 iterations, each run keeping every evaluation) "
                          "needs ");
  expect_refused_promptly("run poisson --epochs 10000000000",
                          "--epochs: must be in [1, 1000000000]");
  // Rules without a Jacobian take any batch the samples allow.
  const Outcome adam = run("run heat-inverse --optimizers adam --batch 4096 --iters 1 "
                           "--train-size 16 --test-size 8 --out adam");
  EXPECT_EQ(adam.exit_code, 0) << adam.err;
}

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

// Numbers at the ends of their range: a subnormal is read as itself, a real that would read 0 or
// overflow and a whole number beyond 64 bits are named, and settings whose untrained loss
// overflows name the run.
TEST_F(Hostile, ExtremeRealsAreReadAsGivenOrNamed) {
  const Outcome tiny = run("run comparison --iters 2 --lr 1e-310 --out tiny");
  EXPECT_EQ(tiny.exit_code, 0) << tiny.err;
  expect_refused("run comparison --lr 1e-400",
                 "--lr: '1e-400' is too close to 0 for a double (it would read 0)");
  expect_refused("run comparison --lr 1e400", "--lr: '1e400' is out of the range of a double");
  expect_refused("run comparison --seed 18446744073709551615",
                 "--seed: must be in [0, 4294967295], got '18446744073709551615'");
  expect_refused("run sin-rotation --phi 1e308", "--phi: must be in [-360, 360], got '1e308'");
  expect_refused("run hig-toy --seeds 1 --iters 2 --lambda 1e308 --out lambda",
                 "run 0 (adam, λ=1e+308, seed 0): the untrained network's train loss is not "
                 "finite");
}

TEST_F(Hostile, ListValuesThatReadTheSameInLabelsAreRefused) {
  expect_refused("run hig-toy --lambda 1,1", "--lambda: '1' is listed twice");
  expect_refused("run hig-toy --lambda 0.01,0.010001",
                 "--lambda: '0.01' and '0.010001' both read '0.01' in labels and file names");
  expect_refused("run sin-rotation --xi 32,32.0001", "--xi: '32' and '32.0001' both read '32'");
  expect_refused("run scaled-toy --alpha 10,1e1", "--alpha: '10' and '1e1' both read '10'");
  expect_refused("run hig-toy --config " + write_config("c.json", R"({"lambda": [1, 1.0]})"),
                 "--lambda: '1' is listed twice");
  // Coordinates of one point may repeat.
  const Outcome point = run("run comparison --start 1,1 --iters 2 --out point");
  EXPECT_EQ(point.exit_code, 0) << point.err;
}

TEST_F(Hostile, StartsAtAMinimumOrWithoutAFiniteLossAreRefused) {
  expect_refused("run comparison --start 0,0", "--start: the loss at (0, 0) is 0: already a minimum");
  expect_refused("run comparison --start 0,1e-200", "--start: the loss at (0, 1e-200) is 0");
  expect_refused("run comparison --start 1e200,1", "--start: the loss at (1e+200, 1) is inf");
  expect_refused("run scaled-toy --start 1e300,1", "is inf with α = 1");
  expect_refused("run sensitivity --start 1e-200", "the loss at 1e-200 is 0 with α = 0.01");
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
        physgrad::experiments::install_interrupt_handlers(0.2);
        ::raise(SIGINT);
        for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
      },
      ::testing::KilledBySignal(SIGINT), "SIGINT: no stop point reached within 0.2 s");
}

TEST_F(InterruptDeathTest, ARunThatReachesAStopPointEndsInItsOwnTime) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        physgrad::experiments::install_interrupt_handlers(0.2);
        ::raise(SIGTERM);
        if (!physgrad::experiments::stop_flag().load()) std::_Exit(1);
        physgrad::experiments::stop_point_reached();
        std::this_thread::sleep_for(std::chrono::milliseconds(600));  // saving, past the grace
        std::_Exit(physgrad::experiments::received_signal() == SIGTERM ? 7 : 1);
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
