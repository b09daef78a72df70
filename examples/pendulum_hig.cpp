// A network learns to steer a user-defined simulator (the pendulum of pendulum.hpp) to target
// states: its hand-written VJP checked first, then training with Adam and with HIG.
#include <chrono>
#include <cstdio>

#include "pendulum.hpp"
#include "physgrad/physgrad.hpp"

namespace {

using example::Index;
using example::Matrix;
using example::Vector;

// Mean wall seconds of one call of f over `repeats` calls.
template <typename F>
double seconds_per_call(F f, int repeats) {
  const auto start = std::chrono::steady_clock::now();
  for (int r = 0; r < repeats; ++r) f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / repeats;
}

}  // namespace

int main() {
  const example::PendulumConfig config;
  const example::Pendulum pendulum(config);

  // The hand-written VJP against central differences of forward().
  const Vector u = Vector::LinSpaced(config.steps, -1.0, 1.0);
  const Vector s0{{0.3, -0.2}};
  const physgrad::DerivativeCheck check = physgrad::check_derivatives(pendulum, u, s0);
  std::printf("derivative check: %s\n", check.report().c_str());
  if (!check.passed) return 1;

  // The same VJP from forward-mode duals (physgrad::AutoDiffSimulator), and what each costs
  // on 256 samples: the dual VJP needs the whole Jacobian, so its cost grows with K.
  for (const Index steps : {Index{20}, Index{160}}) {
    const example::PendulumConfig timing_config{steps, 2.0 / static_cast<double>(steps)};
    const example::Pendulum hand(timing_config);
    const physgrad::AutoDiffSimulator dual(example::PendulumFunction{timing_config},
                                           "pendulum_dual", steps, 2, 2);
    const Matrix controls = Matrix::Random(steps, 256), cotangents = Matrix::Random(2, 256);
    const Matrix initial = example::make_pendulum_tasks(256, 3).context;
    const double difference = (dual.vjp_batch(controls, initial, cotangents) -
                               hand.vjp_batch(controls, initial, cotangents))
                                  .cwiseAbs()
                                  .maxCoeff();
    const int repeats = static_cast<int>(4000 / steps);
    const double hand_time =
        seconds_per_call([&] { hand.vjp_batch(controls, initial, cotangents); }, repeats);
    const double dual_time =
        seconds_per_call([&] { dual.vjp_batch(controls, initial, cotangents); }, repeats);
    std::printf("K = %3td: VJP of 256 samples hand-written %.3f ms, duals %.3f ms (%.1fx), "
                "max difference %.1e\n",
                steps, 1e3 * hand_time, 1e3 * dual_time, dual_time / hand_time, difference);
  }

  // Training: mean_i ½‖P(f(s₀ᵢ, s*ᵢ; θ); s₀ᵢ) − s*ᵢ‖² over θ.
  const physgrad::Dataset train_set = example::make_pendulum_tasks(512, 1);
  const physgrad::Dataset test_set = example::make_pendulum_tasks(128, 2);
  const physgrad::L2Loss loss;
  const physgrad::LearningProblem problem{&pendulum, &loss};
  physgrad::TrainerOptions options;
  options.batch_size = 32;
  options.max_iterations = 400;
  for (const auto& [id, lr] : {std::pair{"adam", 1e-2}, std::pair{"hig", 1.0}}) {
    physgrad::Mlp network({4, 32, config.steps}, physgrad::Activation::kTanh);
    network.initialize(7);
    auto update = physgrad::make_learning_update(id, {{"lr", lr}});
    const physgrad::TrainingSummary summary =
        physgrad::train(network, *update, problem, train_set, &test_set, options);
    const physgrad::TrainingRecord& first = summary.history.front();
    const physgrad::TrainingRecord& last = summary.history.back();
    std::printf("%-4s final loss %.3e (test %.3e, start %.3e), %lld iterations, %.2f s\n", id,
                last.train_loss, last.test_loss, first.train_loss, summary.iterations,
                summary.train_seconds);
  }
  return 0;
}
