// The pendulum of pendulum.hpp given a local inverse (Gauss-Newton from the guess), and a
// network trained with scale-invariant physics (SIP) updates next to Adam.
#include <cstdio>

#include "pendulum.hpp"
#include "physgrad/physgrad.hpp"

namespace {

using example::Vector;

// The pendulum with a local inverse P⁻¹(y; u₀): Gauss-Newton steps u ← u + J⁺(y − P(u)) from
// the guess u₀. Each step is the smallest change of u that meets the linearized target, so the
// controls found stay near the guess.
class InvertiblePendulum final : public example::Pendulum {
 public:
  using Pendulum::Pendulum;

  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector& u0, const Vector& s0) const override {
    Vector u = u0;
    for (int iteration = 0; iteration < 10; ++iteration) {
      const Vector residual = y - forward(u, s0);
      if (residual.norm() <= 1e-12 * (1 + y.norm())) break;
      u += physgrad::power_pinv_apply(jacobian(u, s0), residual);
    }
    return u;
  }
};

}  // namespace

int main() {
  const example::PendulumConfig config;
  const InvertiblePendulum pendulum(config);

  // The inverse reproduces y, and matches the library's numerical Gauss-Newton inverse.
  const Vector u0 = Vector::Zero(config.steps), s0{{0.3, -0.2}}, y{{-0.4, 0.5}};
  const Vector own = pendulum.inverse(y, u0, s0);
  const physgrad::LocalInverseResult library = physgrad::local_inverse(
      pendulum, y, u0, s0, {.method = physgrad::InverseMethod::kInverseGradient});
  std::printf("local inverse: residual %.1e, |u - u0| = %.3f, library gn inverse differs by %.1e\n",
              physgrad::inverse_residual(pendulum, y, u0, s0), (own - u0).norm(),
              (own - library.x).norm());

  // Training: SIP moves each sample's controls towards P⁻¹(y*; u) with Adam on the proxy loss.
  const physgrad::Dataset train_set = example::make_pendulum_tasks(512, 1);
  const physgrad::Dataset test_set = example::make_pendulum_tasks(128, 2);
  const physgrad::L2Loss loss;
  const physgrad::LearningProblem problem{&pendulum, &loss};
  physgrad::TrainerOptions options;
  options.batch_size = 32;
  options.max_iterations = 400;
  for (const char* id : {"adam", "sip"}) {
    physgrad::Mlp network({4, 32, config.steps}, physgrad::Activation::kTanh);
    network.initialize(7);
    auto update = physgrad::make_learning_update(id, {{"lr", 1e-2}});
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
