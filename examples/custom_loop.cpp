// A training loop of one's own around physgrad::train_step: batches drawn here, a step-size
// schedule, logging every 50 steps, and a switch from Adam to HIG halfway (pendulum.hpp's task).
#include <algorithm>
#include <cstdio>
#include <numeric>
#include <random>
#include <vector>

#include "pendulum.hpp"
#include "physgrad/physgrad.hpp"

int main() {
  using physgrad::Index;
  const example::PendulumConfig config;
  const example::Pendulum pendulum(config);
  const physgrad::L2Loss loss;
  const physgrad::LearningProblem problem{&pendulum, &loss};
  const physgrad::Dataset data = example::make_pendulum_tasks(512, 1);

  physgrad::Mlp network({4, 32, config.steps}, physgrad::Activation::kTanh);
  network.initialize(7);
  const auto adam = physgrad::make_learning_update("adam", {{"lr", 1e-2}});
  const auto hig = physgrad::make_learning_update("hig", {{"lr", 1.0}});

  physgrad::StepState state;  // the numerical guard's memory and the network cache
  std::mt19937_64 rng(3);
  std::vector<Index> order(static_cast<std::size_t>(data.size()));
  std::iota(order.begin(), order.end(), Index{0});
  constexpr int kSteps = 400, kBatch = 32;
  std::printf("start loss %.3e\n", physgrad::mean_loss(network, problem, data));
  for (int step = 0; step < kSteps; ++step) {
    // Adam with a step size halved every 100 steps, then HIG for the second half.
    physgrad::LearningUpdate& rule = step < kSteps / 2 ? *adam : *hig;
    if (step > 0 && step % 100 == 0 && step < kSteps / 2) {
      adam->set_learning_rate(0.5 * adam->learning_rate());
    }
    const Index first = (step * kBatch) % data.size();
    if (first == 0) std::shuffle(order.begin(), order.end(), rng);
    const std::vector<Index> batch(order.begin() + first, order.begin() + first + kBatch);
    const physgrad::StepReport report =
        physgrad::train_step(network, rule, problem, data.select(batch), state);
    if (!report.applied()) {
      std::printf("stopped: %s\n", physgrad::describe_failure(report, step).c_str());
      return 1;
    }
    if ((step + 1) % 50 == 0) {
      std::printf("step %3d  %-4s lr %.2g  batch loss %.3e  loss %.3e  %.1f ms/step\n", step + 1,
                  rule.id().c_str(), rule.learning_rate(), report.loss,
                  physgrad::mean_loss(network, problem, data), 1e3 * report.total_seconds);
    }
  }
  std::printf("final loss %.3e\n", physgrad::mean_loss(network, problem, data));
  return 0;
}
