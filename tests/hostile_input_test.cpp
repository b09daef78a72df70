// The command line against hostile input: control characters and bytes that are not UTF-8 in
// any text value, files that are not plain files or are too large, crafted checkpoints (deep
// nesting, missing or null values), sizes beyond memory, list values that collide as labels,
// starts without a finite loss, unknown subcommands. Each is one line on stderr naming the value,
// exit code 2, nothing written and nothing blocked. (Stop signals: hostile_stop_test.cpp.)
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <nlohmann/json.hpp>

#include "hostile_fixture.hpp"
#include "physgrad/io/checkpoint_file.hpp"

namespace {

using physgrad::testing::Hostile;
using physgrad::testing::Outcome;
using physgrad::testing::read_file;
namespace fs = std::filesystem;

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
  with([](nlohmann::json& d) { d["current"]["state"]["summary"]["wall_seconds"] = -1; },
       "checkpoint field 'wall_seconds': must be a finite time ≥ 0");
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
  expect_refused("run heat-inverse --network mlp --dims 1 --n 1000000",
                 "--n: 1000000 cells (a network of ~8·1000000²");
  expect_refused("run heat-inverse --n 1000000",
                 "--n: 1000000 cells per axis (one sample's U-net activations) needs ");
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
  expect_refused_promptly("run heat-inverse --network mlp --dims 1 --optimizers hig --batch 4096 "
                          "--train-size 4096",
                          "--batch: 4096 (a gn or hig step forms a 33088² matrix from 262144 "
                          "Jacobian rows of 33088 weights) needs ");
  expect_refused_promptly("run heat-inverse --network mlp --dims 1 --optimizers adam,gn "
                          "--batch 256 --train-size 256",
                          "--batch: 256 (a gn or hig step forms a 16384² matrix from 16384 "
                          "Jacobian rows of 33088 weights) takes 4.571e+12 multiply-adds, more "
                          "than the 1e+12");
  expect_refused_promptly("run hig-toy --iters 1000000000 --eval-every 1",
                          "--eval-every: 1 (1e+09 iterations, each run keeping every evaluation) "
                          "needs ");
  expect_refused_promptly("run poisson --epochs 10000000000",
                          "--epochs: must be in [1, 1000000000]");
  // The U-net's Jacobian (B·4096 rows of 37 697 weights) with batch norm off; with it on, the
  // Jacobian rules are refused whatever the batch.
  expect_refused_promptly("run heat-inverse --batch-norm off --optimizers hig --batch 16",
                          "--batch: 16 (a gn or hig step forms a 37249² matrix from 65536 "
                          "Jacobian rows of 37249 weights)");
  expect_refused_promptly("run heat-inverse --optimizers adam,hig",
                          "--optimizers: 'hig' needs per-sample Jacobians, which batch norm");
  // The structured rules need the per-sample cotangents too (factors, J w products).
  for (const std::string id : {"kfac-hig", "lanczos-hig"}) {
    expect_refused_promptly("run heat-inverse --optimizers adam," + id,
                            "--optimizers: '" + id + "' needs per-sample Jacobians");
  }
  // They hold the 4096 output cotangents of each sample's 64×64 field, 2^30 doubles per 8
  // samples (a batch counts up to the training set's size), twice counted: ~1 TiB here.
  expect_refused_promptly("run heat-inverse --batch-norm off --optimizers kfac-hig --batch 4096 "
                          "--train-size 4096",
                          "--batch: 4096 (the stacked Jacobian of 'kfac-hig' holds 4096 output "
                          "cotangents of every sample's field) needs ");
  // --samples counts output directions: a value that is not one is named.
  expect_refused_promptly("run heat-inverse --batch-norm off --optimizers kfac-hig --samples 2.5",
                          "--samples: '2.5' is not a whole number");
  expect_refused_promptly("run heat-inverse --batch-norm off --optimizers kfac-hig --samples -1",
                          "--samples: must be in [0, 2147483647], got '-1'");
  // Rules without a Jacobian take any batch the samples allow.
  const Outcome adam = run("run heat-inverse --network mlp --dims 1 --optimizers adam --batch "
                           "4096 --iters 1 --train-size 16 --test-size 8 --data fixed --out adam");
  EXPECT_EQ(adam.exit_code, 0) << adam.err;
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

}  // namespace
