// Learning case — what a learning experiment trains, declared once: physics P, loss L, the
// network f_θ a run of seed s starts from, and samples (training stream 2s, test stream 2s + 1).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "physgrad/loss/loss.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/physics/simulator.hpp"
#include "physgrad/run/cases/learning_runs.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad::run {

struct ReferenceCase;  // learning_experiment.hpp

// An experiment's run() trains on it (LearningSweep takes its rule defaults and, for --data
// fresh, its samples) and its reference() is the case at one batch: so the problem `physgrad
// bench` times is the one the experiment trains.
struct LearningCase {
  std::shared_ptr<const Simulator> physics;
  std::shared_ptr<const Loss> loss;
  // The network a run with --seed `seed` starts from, initialized.
  std::function<Mlp(std::uint64_t seed)> network;
  // `count` samples of random stream `stream` (trainer.hpp).
  SampleSource samples;
  std::map<std::string, RuleDefaults> defaults;  // lr, batch and τ of each rule

  LearningProblem problem() const { return {physics.get(), loss.get()}; }
  // The training set of seed s: stream 2s; the test set: stream 2s + 1.
  Dataset training_set(Index count, std::uint64_t seed) const;
  Dataset test_set(Index count, std::uint64_t seed) const;
  // The case at one batch: the first `batch` samples of the training set of `seed` and the
  // network of `seed`.
  ReferenceCase reference(Index batch, std::uint64_t seed) const;
};

}  // namespace physgrad::run
