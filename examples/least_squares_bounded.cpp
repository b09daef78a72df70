// A bounded, badly scaled least-squares fit: a projectile with quadratic air drag, launched at
// speed v₀ ≈ 45 m/s, angle α ≈ 0.9 rad, drag k ≈ 2.5e-3 1/m (k ≥ 0 by a bound), fitted to noisy
// positions by every direct rule, with and without x_scale, stopped by Ceres-style tolerances.
#include <cmath>
#include <cstdio>
#include <string>

#include "physgrad/physgrad.hpp"

using physgrad::Index;
using physgrad::Vector;

// Positions (x, y) at t = 0.25, 0.5, …, 5 s of a projectile from the origin, x = (v₀, α, k):
// r̈ = −g ŷ − k |ṙ| ṙ, integrated by RK4 with 0.05 s steps. Written once for any scalar type.
struct Projectile {
  static constexpr int kSamples = 20;
  static constexpr int kStepsPerSample = 5;
  static constexpr double kDt = 0.05, kGravity = 9.81;

  template <typename T>
  Eigen::Matrix<T, Eigen::Dynamic, 1> operator()(const Eigen::Matrix<T, Eigen::Dynamic, 1>& p,
                                                 const Vector& /*context*/) const {
    using std::cos;
    using std::sin;
    using std::sqrt;
    using State = Eigen::Matrix<T, 4, 1>;  // x, y, vx, vy
    const T k = p(2);
    const auto rate = [&k](const State& s) {
      const T speed = sqrt(s(2) * s(2) + s(3) * s(3));
      State d;
      d << s(2), s(3), -k * speed * s(2), -kGravity - k * speed * s(3);
      return d;
    };
    State s;
    s << T(0.0), T(0.0), p(0) * cos(p(1)), p(0) * sin(p(1));
    Eigen::Matrix<T, Eigen::Dynamic, 1> out(2 * kSamples);
    for (int i = 0; i < kSamples; ++i) {
      for (int n = 0; n < kStepsPerSample; ++n) {
        const State k1 = rate(s), k2 = rate(State(s + 0.5 * kDt * k1));
        const State k3 = rate(State(s + 0.5 * kDt * k2)), k4 = rate(State(s + kDt * k3));
        s += (kDt / 6) * (k1 + 2 * k2 + 2 * k3 + k4);
      }
      out(2 * i) = s(0);
      out(2 * i + 1) = s(1);
    }
    return out;
  }
};

struct Fit {
  int iterations = 0;
  int evaluations = 0;
  bool reached = false;
  bool feasible = true;
  double loss = 0;
  std::string note;
};

// Runs one rule; `reached` when it gets within 1e-6 of the best loss.
Fit fit(const std::string& id, const physgrad::RuleSettings& settings,
        const physgrad::Objective& objective, const Vector& start,
        physgrad::MinimizeOptions options, int budget) {
  auto rule = physgrad::make_optimizer(id, settings);
  options.max_iterations = budget;
  const physgrad::MinimizeSummary s = physgrad::minimize(*rule, objective, start, options);
  Fit out{s.iterations, s.evaluations, s.termination == physgrad::Termination::kConverged, true,
          s.loss, ""};
  for (const physgrad::IterationRecord& record : s.history) {
    if (record.x(2) < 0) out.feasible = false;
  }
  if (!out.reached) out.note = physgrad::to_string(s.termination);
  return out;
}

// The first-order rules have a step size to choose: the fewest iterations over η = 10⁻ʲ,
// j = 0, …, 12 (once one step size reaches the loss, the others need only run as long).
Fit best_step_size(const std::string& id, const physgrad::Objective& objective,
                   const Vector& start, const physgrad::MinimizeOptions& options, int budget,
                   double& best_lr) {
  Fit best{budget, 0, false, true, INFINITY, ""};
  for (int j = 0; j <= 12; ++j) {
    const double lr = std::pow(10.0, -j);
    const Fit f = fit(id, {{"lr", lr}}, objective, start, options,
                      best.reached ? best.iterations : budget);
    if (!f.feasible) best.feasible = false;
    if (!best.reached && f.loss < best.loss) best.loss = f.loss;
    if (f.reached && (!best.reached || f.iterations < best.iterations)) {
      const bool feasible = best.feasible;
      best = f;
      best.feasible = feasible;
      best_lr = lr;
    }
  }
  if (!best.reached) {
    char note[64];
    std::snprintf(note, sizeof note, "lowest loss %.4g", best.loss);
    best.note = note;
  }
  return best;
}

int main() {
  // Noisy positions of v₀ = 45, α = 0.9, k = 2.5e-3.
  const physgrad::AutoDiffSimulator model(Projectile{}, "projectile", 3, 2 * Projectile::kSamples);
  Vector data = model.forward(Vector{{45.0, 0.9, 2.5e-3}});
  for (Index i = 0; i < data.size(); ++i) data(i) += 0.3 * std::sin(1.7 * static_cast<double>(i));
  const physgrad::L2Loss loss;
  const physgrad::Objective objective(model, loss, data);
  const Vector start{{30.0, 0.6, 0.0}};  // no drag: k starts on its bound

  physgrad::MinimizeOptions options;
  options.lower = Vector{{0.0, 0.0, 0.0}};  // v₀, α, k ≥ 0
  options.upper = Vector{{INFINITY, 1.5, INFINITY}};
  const Vector x_scale{{10.0, 0.1, 1e-3}};  // the size of change each parameter needs

  // The best fit: Levenberg-Marquardt with x_scale until the loss stops changing.
  physgrad::MinimizeOptions tight = options;
  tight.x_scale = x_scale;
  tight.function_tolerance = 1e-15;
  tight.parameter_tolerance = 1e-15;
  tight.max_iterations = 500;
  auto lm = physgrad::make_optimizer("lm");
  const physgrad::MinimizeSummary best = physgrad::minimize(*lm, objective, start, tight);
  std::printf("%s\n", physgrad::full_report(best).c_str());
  std::printf("best fit: v0 = %.4f, alpha = %.5f, k = %.6f, loss %.6e\n\n", best.x(0), best.x(1),
              best.x(2), best.loss);

  // Iterations of every rule to come within 1e-6 of that loss, without and with x_scale.
  options.loss_tolerance = best.loss * (1 + 1e-6);
  const int budget = 10000;
  std::printf("iterations (evaluations) to reach L <= (1 + 1e-6) L*, at most %d:\n", budget);
  std::printf("%-9s %-28s %-28s\n", "rule", "without x_scale", "with x_scale");
  bool all_feasible = true;
  for (const std::string& id : physgrad::rule_ids(physgrad::RuleKind::kDirect)) {
    std::string cells[2];
    for (int scaled = 0; scaled < 2; ++scaled) {
      physgrad::MinimizeOptions run = options;
      if (scaled) run.x_scale = x_scale;
      double lr = 0;
      const bool first_order = id == "gd" || id == "momentum" || id == "adam";
      const Fit f = first_order ? best_step_size(id, objective, start, run, budget, lr)
                                : fit(id, {}, objective, start, run, budget);
      all_feasible = all_feasible && f.feasible;
      char cell[64];
      if (f.reached && first_order) {
        std::snprintf(cell, sizeof cell, "%d (%d), lr %.0e", f.iterations, f.evaluations, lr);
      } else if (f.reached) {
        std::snprintf(cell, sizeof cell, "%d (%d)", f.iterations, f.evaluations);
      } else {
        std::snprintf(cell, sizeof cell, "- (%s)", f.note.c_str());
      }
      cells[scaled] = cell;
    }
    std::printf("%-9s %-28s %-28s\n", id.c_str(), cells[0].c_str(), cells[1].c_str());
  }
  std::printf("\nk >= 0 at every iterate of every run: %s\n", all_feasible ? "yes" : "no");
  return all_feasible ? 0 : 1;
}
