// Checkpoint files and the states inside them: values come back bit-identical; every
// truncation or corruption of the bytes is an Error naming the file; and a seeded fuzz of the
// document itself (valid checksum, damaged content) gives a usable state or an Error, never a
// crash or another exception. Bounded: a few thousand inputs, about a second.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "physgrad/run/life/checkpoint.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "physgrad/io/serialize.hpp"
#include "physgrad/io/checkpoint_file.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad {
namespace {

namespace fs = std::filesystem;

class CheckpointFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("physgrad_checkpoint_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string bytes_of(const fs::path& path) const {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  }
  void write_bytes(const fs::path& path, const std::string& bytes) const {
    std::ofstream(path, std::ios::binary) << bytes;
  }
  // Reading `bytes` as a checkpoint throws Error naming its source.
  static void expect_rejected(const std::string& bytes, const std::string& what) {
    try {
      parse_checkpoint(bytes, "damaged.pgc");
      ADD_FAILURE() << what << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("checkpoint 'damaged.pgc': "), std::string::npos)
          << e.what();
    }
  }

  fs::path dir_;
};

// A trainer state after a few Adam steps of a 1 → 4 → 2 network through y = diag(1, 0.01) x.
struct SmallRun {
  DiagonalScale physics{Vector{{1.0, 0.01}}};
  L2Loss loss;
  Mlp network{{1, 4, 2}, Activation::kTanh};
  Dataset data;
  TrainerState state;

  SmallRun() {
    network.initialize(1);
    data.inputs = Vector::LinSpaced(12, -1, 1).transpose();
    data.targets = Matrix(2, 12);
    data.targets << data.inputs, data.inputs.array().square().matrix() * 0.01;
    TrainerOptions options;
    options.batch_size = 4;
    options.max_iterations = 8;
    options.checkpoint_every = 5;
    options.on_checkpoint = [this](const TrainerState& s) { state = s; };
    const auto adam = make_learning_update("adam");
    train(network, *adam, {&physics, &loss}, data, nullptr, options);
    network.initialize(1);
  }
  // Resumes from `s` for a few iterations; throws Error when the state does not fit.
  void resume(const TrainerState& s) {
    TrainerOptions options;
    options.batch_size = 4;
    options.max_iterations = 10;
    options.resume = &s;
    const auto adam = make_learning_update("adam");
    train(network, *adam, {&physics, &loss}, data, nullptr, options);
  }
};

TEST_F(CheckpointFile, RoundTripIsBitIdentical) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::uint64_t> bits;
  Vector values(2000);
  for (Index i = 0; i < values.size(); ++i) {
    double v;
    do {
      const std::uint64_t b = bits(rng);
      std::memcpy(&v, &b, sizeof v);
    } while (!std::isfinite(v));
    values[i] = v;  // every exponent, subnormals included
  }
  values[0] = std::numeric_limits<double>::denorm_min();
  values[1] = -0.0;
  const fs::path path = dir_ / "state.pgc";
  write_checkpoint_file(path, {{"values", vector_to_json(values)}});
  const Vector back = vector_from_json(read_checkpoint_file(path), "values", values.size());
  for (Index i = 0; i < values.size(); ++i) {
    EXPECT_EQ(std::memcmp(&values[i], &back[i], sizeof(double)), 0) << i << ": " << values[i];
  }
}

TEST_F(CheckpointFile, EveryTruncationAndByteChangeIsAnError) {
  SmallRun run;
  const fs::path path = dir_ / "state.pgc";
  write_checkpoint_file(path, trainer_state_to_json(run.state));
  const std::string good = bytes_of(path);
  ASSERT_NO_THROW(read_checkpoint_file(path));

  for (std::size_t length = 0; length < good.size(); length += 1 + length / 64) {
    expect_rejected(good.substr(0, length), "truncation to " + std::to_string(length));
  }
  // The state holds measured times, so its bytes differ from run to run; the header's bytes
  // are changed on purpose as well as random ones.
  for (const std::string& header_change : {std::string("physgrad-checkpoint  1"),
                                           std::string("physgrad-checkpoint 01"),
                                           std::string("physgrad-checkpoint +1")}) {
    expect_rejected(header_change + good.substr(21), header_change);
  }
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<std::size_t> position(0, good.size() - 1);
  std::uniform_int_distribution<int> byte(0, 255);
  int tried = 0;
  for (int k = 0; k < 1500; ++k) {
    std::string damaged = good;
    const std::size_t at = position(rng);
    switch (k % 3) {
      case 0: damaged[at] = static_cast<char>(byte(rng)); break;
      case 1: damaged.erase(at, 1); break;
      default: damaged.insert(at, 1, static_cast<char>(byte(rng))); break;
    }
    if (damaged == good) continue;
    expect_rejected(damaged, "change " + std::to_string(k));
    ++tried;
  }
  EXPECT_GT(tried, 1400);
  expect_rejected("", "an empty file");
  expect_rejected("physgrad-checkpoint 2 2 0000000000000000\n{}", "another version");
  EXPECT_THROW(read_checkpoint_file(dir_ / "missing.pgc"), Error);
  // On disk: the bytes written are the ones checked.
  write_bytes(dir_ / "cut.pgc", good.substr(0, good.size() - 1));
  EXPECT_THROW(read_checkpoint_file(dir_ / "cut.pgc"), Error);
}

// Random damage to a JSON value: drop a key, change a type, a sign or a size.
void mutate(nlohmann::json& value, std::mt19937_64& rng) {
  std::uniform_int_distribution<int> pick(0, 9);
  if (value.is_object() && !value.empty()) {
    auto it = value.begin();
    std::advance(it, std::uniform_int_distribution<std::size_t>(0, value.size() - 1)(rng));
    if (pick(rng) == 0) {
      value.erase(it);
    } else {
      mutate(*it, rng);
    }
    return;
  }
  if (value.is_array() && !value.empty()) {
    const int choice = pick(rng);
    if (choice == 0) {
      value.erase(value.begin());
    } else if (choice == 1) {
      value.push_back(value.back());
    } else {
      mutate(value[std::uniform_int_distribution<std::size_t>(0, value.size() - 1)(rng)], rng);
    }
    return;
  }
  static const nlohmann::json replacements[] = {
      nullptr, true, "text", -1, 0, 1e308, -1e308, 2.5, nlohmann::json::array(),
      nlohmann::json::object(), 1000000000000LL};
  value = replacements[std::uniform_int_distribution<std::size_t>(0, 10)(rng)];
}

TEST_F(CheckpointFile, DamagedStatesResumeOrThrowErrorOnly) {
  SmallRun run;
  const nlohmann::json good = trainer_state_to_json(run.state);
  const Index count = run.network.num_parameters();
  std::mt19937_64 rng(5);
  int accepted = 0, rejected = 0;
  for (int k = 0; k < 1500; ++k) {
    nlohmann::json damaged = good;
    for (int changes = 1 + k % 3; changes > 0; --changes) mutate(damaged, rng);
    try {
      run.resume(trainer_state_from_json(damaged, count));
      ++accepted;
    } catch (const Error&) {
      ++rejected;
    }
  }
  // Many changes hit a value the state check or the training loop refuses; some (a changed
  // recorded time, say) leave a state that resumes.
  EXPECT_GT(rejected, 500);
  EXPECT_GT(accepted, 10);
}

TEST_F(CheckpointFile, DamagedExperimentCheckpointsAreErrorsOnly) {
  SmallRun run;
  const nlohmann::json config = {
      {"experiment", "hig-toy"}, {"command", "physgrad run hig-toy"}, {"settings", {{"lr", nullptr}}}};
  const run::RunKey key{0, "adam", "λ=1", 0};
  const nlohmann::json good = {
      {"experiment", "hig-toy"},
      {"settings", {{"lr", nullptr}}},
      {"finished", nlohmann::json::array()},
      {"current", {{"key", key.json()}, {"state", trainer_state_to_json(run.state)}}}};
  const Index count = run.network.num_parameters();
  {
    const run::ExperimentCheckpoint checkpoint(nullptr, config, good);
    ASSERT_TRUE(checkpoint.in_progress(key, count).has_value());
    EXPECT_FALSE(checkpoint.finished(key, count).has_value());
    const run::RunKey other{0, "hig", "λ=1", 0};
    EXPECT_THROW(checkpoint.in_progress(other, count), Error);
  }
  std::mt19937_64 rng(3);
  int rejected = 0;
  for (int k = 0; k < 1000; ++k) {
    nlohmann::json damaged = good;
    mutate(damaged, rng);
    try {
      const run::ExperimentCheckpoint checkpoint(nullptr, config, damaged);
      checkpoint.finished(key, count);
      checkpoint.in_progress(key, count);
    } catch (const Error&) {
      ++rejected;
    }
  }
  EXPECT_GT(rejected, 300);
}

}  // namespace
}  // namespace physgrad
