// time-reversal: recover the initial state x of a simulation from its final state y* = P(x*).
// PG through the simulator's time reversal R (anchored: P⁻¹(y; x) = x + R(y) − R(P(x))) against
// PG through numerical local inverses (L-BFGS, Gauss-Newton) and Gauss-Newton, LM and GD, on a
// velocity-Verlet FPU chain (reversible: R is exact to rounding) and on RK4 coupled oscillators
// (R is exact only to RK4's truncation error), by iterations, simulator passes and time.
#include <algorithm>
#include <cmath>
#include <map>

#include "physgrad/catalogue.hpp"
#include "physgrad/run/cases/direct_runs.hpp"
#include "framework.hpp"
#include "registry.hpp"
#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/physics/coupled_oscillators.hpp"
#include "physgrad/report/significant.hpp"
#include "physgrad/physics/fpu_chain.hpp"
#include "physgrad/run/cases/sampling.hpp"

namespace physgrad::experiments {
namespace {
namespace time_reversal_case {

// One inverse problem: the simulator, its context (the controls), the true and the start state.
struct Problem {
  std::string key, title;
  std::unique_ptr<Simulator> physics;
  Vector context, x_true, x0;
};

Problem make_problem(const std::string& key, const Settings& settings, std::uint64_t seed) {
  Sampler sampler(seed);
  const auto draw = [&sampler](Index n, double lo, double hi) {
    Vector v(n);
    for (Index i = 0; i < n; ++i) v(i) = sampler.uniform(lo, hi);
    return v;
  };
  Problem p;
  p.key = key;
  if (key == "fpu") {
    const FpuChainConfig config{settings.integer("masses"), settings.integer("fpu-steps"), 0.1,
                                1.0};
    p.physics = std::make_unique<FpuChain>(config);
    const double a = settings.real("amplitude");
    p.x_true = draw(p.physics->input_dim(), -a, a);
    p.title = "FPU chain, " + std::to_string(config.masses) + " masses, " +
              std::to_string(config.steps) + " Verlet steps";
  } else {
    OscillatorConfig config = OscillatorConfig::paper();
    config.steps = settings.integer("osc-steps");
    config.input = OscillatorInput::kInitialState;
    p.physics = std::make_unique<CoupledOscillators>(config);
    p.context = draw(config.steps, -1, 1);
    p.x_true = draw(p.physics->input_dim(), 0, 1);
    p.title = "coupled oscillators, " + std::to_string(config.steps) + " RK4 steps";
  }
  p.x0 = Vector::Zero(p.physics->input_dim());
  return p;
}

// N·Nt of the FPU chain: one simulator pass then takes about 30 s.
constexpr double kMaxMassSteps = 1e9;
// What each coordinate of an iterate holds: its entry in the iterate and in the metrics row
// (167 B measured over 10 iterates of 2·10⁵ coordinates).
constexpr double kCoordinateBytes = 170;

// Samples in the widest simulator call of the selected rules on a state of `dim` values:
// a rule that forms the Hessian (RuleDerivative, newton) 2·dim VJPs, one that forms the whole
// Jacobian dim (gn, lm, ig; PG through the inverse-gradient inverse), every other rule one sample
// at a time.
double widest_batch(const Settings& settings, double dim) {
  double widest = 1;
  const std::vector<std::string> inverses = settings.texts("pg-inverse");
  const bool pg_ig = std::find(inverses.begin(), inverses.end(), "ig") != inverses.end();
  for (const std::string& id : settings.texts("optimizers")) {
    const RuleDerivative derivative = find_rule(RuleKind::kDirect, id).derivative;
    if (derivative == RuleDerivative::kHessian) widest = std::max(widest, 2 * dim);
    if (derivative == RuleDerivative::kJacobian || (id == "pg" && pg_ig)) {
      widest = std::max(widest, dim);
    }
  }
  return widest;
}

// The runs per problem: one per rule, PG one per local inverse.
double runs_per_problem(const Settings& settings) {
  double runs = 0;
  for (const std::string& id : settings.texts("optimizers")) {
    runs += id == "pg" ? static_cast<double>(settings.texts("pg-inverse").size()) : 1;
  }
  return runs;
}

bool has_problem(const Settings& settings, const std::string& key) {
  const std::vector<std::string> problems = settings.texts("problems");
  return std::find(problems.begin(), problems.end(), key) != problems.end();
}

// Per mass of the FPU chain: the positions the widest VJP keeps (Nt + 1 per sample), a 2N × 2N
// Jacobian or Hessian with three copies for its factorisation, every iterate's 2 coordinates
// per mass in every run, and the chain's own state and work arrays.
double fpu_bytes_per_mass(const Settings& settings) {
  if (!has_problem(settings, "fpu")) return 0;
  const double masses = static_cast<double>(settings.integer("masses"));
  const double steps = static_cast<double>(settings.integer("fpu-steps"));
  const double widest = widest_batch(settings, 2 * masses);
  const double matrix = widest > 1 ? 4 * 8 * 4 * masses : 0;
  const double iterates = static_cast<double>(settings.integer("iters")) + 1;
  return 8 * widest * (steps + 1) + matrix +
         iterates * runs_per_problem(settings) * 2 * kCoordinateBytes + 64;
}

// Per RK4 step of the two oscillators: the positions of its 4 stages (2 values each) and its
// control, for each sample of the widest VJP.
double oscillator_bytes_per_step(const Settings& settings) {
  if (!has_problem(settings, "oscillators")) return 0;
  return 8 * (4 * 2 + 1) * widest_batch(settings, 4);
}

class TimeReversal final : public Experiment {
 public:
  std::string name() const override { return "time-reversal"; }
  std::string description() const override {
    return "initial state from final state: PG through the time-reversed simulator vs PG "
           "through numerical inverses, GN, LM and GD (FPU chain, RK4 oscillators)";
  }
  std::vector<OptionSpec> options() const override {
    return {
        text_list_option("problems", "fpu,oscillators", "the simulations").one_of({"fpu", "oscillators"}),
        text_list_option("pg-inverse", "time_reversal,lbfgs,ig", "local inverses PG runs with, one run each")
            .one_of({"time_reversal", "lbfgs", "ig"}),
        integer_option("masses", "8",
                       "masses N of the FPU chain (N·Nt at most 10⁹: a simulator pass of the "
                       "chain then takes about 30 s; checked against memory with the "
                       "trajectories the rules' VJPs keep)")
            .at_least(1)
            .at_most(kMaxMassSteps)
            .needs_bytes_each(fpu_bytes_per_mass)
            .quick("4"),
        integer_option("fpu-steps", "100",
                       "velocity-Verlet steps Nt of the FPU chain, dt 0.1 (at most 10⁷: a "
                       "simulator pass of the 8-mass chain then takes about 7 s)")
            .at_least(1)
            .at_most(1e7)
            .quick("10"),
        integer_option("osc-steps", "96",
                       "RK4 steps of the oscillators, dt 0.125 (at most 10⁶: a simulator pass "
                       "then takes about 2 s)")
            .at_least(1)
            .at_most(1e6)
            .needs_bytes_each(oscillator_bytes_per_step)
            .quick("8"),
        real_option("amplitude", "0.5", "the FPU chain's true state is drawn from U(−a, a)").above(0),
        real_option("tol", "1e-16", "loss counted as converged").above(0),
    };
  }
  std::vector<std::string> optimizer_choices() const override {
    return rule_ids(RuleKind::kDirect);
  }
  std::vector<std::string> default_optimizers() const override {
    return {"pg", "gn", "lm", "gd"};
  }
  long long default_iterations() const override { return 200; }

  // Every run keeps its iterates (require_iterate_memory); one simulator pass of the chain
  // costs about N·Nt·30 ns (measured at N = 10⁵, Nt = 100; 90 ns at N = 8).
  void validate(const Settings& settings) const override {
    require_iterate_memory(settings, settings.texts("problems").size() *
                                         static_cast<std::size_t>(runs_per_problem(settings)));
    const double mass_steps = static_cast<double>(settings.integer("masses")) *
                              static_cast<double>(settings.integer("fpu-steps"));
    if (has_problem(settings, "fpu") && mass_steps > kMaxMassSteps) {
      throw Error("--masses " + std::to_string(settings.integer("masses")) + " × --fpu-steps " +
                  std::to_string(settings.integer("fpu-steps")) + ": " + format_value(mass_steps) +
                  " mass-steps per simulator pass, more than the 1e+09 (about 30 s a pass) "
                  "this experiment allows");
    }
  }

  void run(const Settings& settings, RunContext& context) const override {
    const auto iterations = static_cast<int>(settings.integer("iters"));
    const double tol = settings.real("tol");
    const auto seed = static_cast<std::uint64_t>(settings.integer("seed"));
    const std::vector<RuleSetup> rules =
        with_pg_inverses(selected_rules(settings, kDefaultLr), settings.texts("pg-inverse"));

    RunContext::Table table{"To the loss " + format_value(tol) + ", at most " +
                                std::to_string(iterations) + " iterations",
                            {"problem", "rule", "step size", "iterations", "simulator passes",
                             "forward / VJP / reversal", "seconds", "final loss"},
                            {}};
    std::uint64_t problem_seed = 2 * seed;
    std::string message, message_figure;  // the first problem's passes figure
    for (const std::string& key : settings.texts("problems")) {
      const Problem problem = make_problem(key, settings, problem_seed++);
      const L2Loss loss;
      const Vector target = problem.physics->forward(problem.x_true, problem.context);
      const Objective objective(*problem.physics, loss, target, problem.context);
      const Vector reversed = problem.physics->time_reversal(target, problem.context);
      context.add_note(problem.title + ": the time reversal of y* reproduces it to ‖P(R(y*)) − y*‖/‖y*‖ = " +
                       format_value((problem.physics->forward(reversed, problem.context) - target).norm() /
                                    target.norm()) +
                       " (start x₀ = 0).");

      // minimize() counts the simulator's work (MinimizeSummary::counts, per iterate in the
      // history). The VJP column holds the VJPs of the default Jacobian (m) and weighted
      // Hessian (2n), which these simulators use.
      const long long outputs = problem.physics->output_dim();
      const long long hessian_vjps = 2 * problem.physics->input_dim();
      const auto passes = [](const IterationRecord& record) {
        return nlohmann::json{{"simulator_passes", record.counts.passes}};
      };
      std::vector<DirectResult> results;
      for (const RuleSetup& rule : rules) {
        context.progress("time-reversal: " + key + ", " + rule.label);
        results.push_back(run_direct(context, rule, objective, problem.x0, iterations, tol,
                                     {{"problem", key}}, passes));
        const DirectResult& r = results.back();
        const SimulatorCounts& counts = r.summary.counts;
        table.rows.push_back({key, r.rule.label, step_size_text(r.rule), iterations_cell(r),
                              std::to_string(counts.passes),
                              std::to_string(counts.forward) + " / " +
                                  std::to_string(counts.vjp + outputs * counts.jacobians +
                                                 hessian_vjps * counts.hessians) +
                                  " / " +
                                  std::to_string(counts.reversals),
                              format_value(r.summary.wall_seconds),
                              format_value(r.summary.loss)});
      }
      add_figures(context, problem, results);
      if (!message.empty()) message += ' ';
      message += fewest_passes_sentence(problem, results, tol);
      if (message_figure.empty()) message_figure = "loss_vs_passes_" + problem.key + ".svg";
    }
    context.finish_progress();
    if (!message_figure.empty()) {
      context.set_message(message_figure, message,
                          {"simulator_passes", "simulator passes, over every problem"});
    }
    context.add_table(std::move(table));
    context.add_note(
        "A simulator pass is one sample's forward integration, VJP (a Jacobian costs one per "
        "output) or time reversal. PG through the time reversal costs one forward and two "
        "reversals per step for the inverse plus the forward passes of the step and its check.");
  }

 private:
  // Which converged rule spent the fewest simulator passes on `problem`, and how many times
  // fewer than the next.
  static std::string fewest_passes_sentence(const Problem& problem,
                                            const std::vector<DirectResult>& results, double tol) {
    std::vector<const DirectResult*> converged;
    for (const DirectResult& r : results) {
      if (r.summary.termination == Termination::kConverged) converged.push_back(&r);
    }
    std::sort(converged.begin(), converged.end(), [](const auto* a, const auto* b) {
      return a->summary.counts.passes < b->summary.counts.passes;
    });
    std::string out = problem.title + ": ";
    if (out[0] >= 'a' && out[0] <= 'z') out[0] = static_cast<char>(out[0] - 'a' + 'A');
    if (converged.empty()) return out + "no rule reached L ≤ " + format_value(tol) + ".";
    const auto passes = [](const DirectResult* r) {
      return static_cast<double>(r->summary.counts.passes);
    };
    out += converged[0]->rule.label + " reaches L ≤ " + format_value(tol) + " in " +
           format_value(passes(converged[0])) + " simulator passes";
    if (converged.size() == 1) return out + ", the only rule that does.";
    return out + ", " + with_digits(passes(converged[1]) / std::max(1.0, passes(converged[0])), 2) +
           "× fewer than " + converged[1]->rule.label + " (" + format_value(passes(converged[1])) +
           ").";
  }

  // Gauss-Newton's (and IG's) steps overshoot on these nonlinear problems from x₀ = 0 at η = 1
  // and 0.5 (measured with the default seed); η = 0.3 converges on both. GD diverges on the
  // oscillators at 0.03.
  inline static const std::map<std::string, double> kDefaultLr = {
      {"gd", 0.01}, {"momentum", 0.01}, {"adam", 0.01}, {"gn", 0.3}, {"ig", 0.3}, {"pg", 1.0}};

  static void add_figures(RunContext& context, const Problem& problem,
                          const std::vector<DirectResult>& results) {
    context.add_figure({"loss_vs_iteration_" + problem.key + ".svg",
                        "Loss per iteration, " + problem.title + ".",
                        loss_curves_svg(results, "Loss vs iteration: " + problem.title)});
    const auto curves = [&](bool by_time) {
      return loss_curves_svg(
          results, (by_time ? "Loss vs time: " : "Loss vs simulator passes: ") + problem.title,
          by_time ? "wall seconds" : "simulator passes (forward, VJP, reversal)",
          [&](std::size_t r, std::size_t k) -> double {
            const IterationRecord& record = results[r].summary.history[k];
            return by_time ? record.seconds : static_cast<double>(record.counts.passes);
          },
          !by_time);
    };
    context.add_figure({"loss_vs_passes_" + problem.key + ".svg",
                        "Loss against the simulator passes spent (log axis), " + problem.title +
                            ". The loss holds until the next iterate: the passes in between "
                            "(line searches, inner solves of a local inverse) move no iterate.",
                        curves(false)});
    context.add_figure({"loss_vs_time_" + problem.key + ".svg",
                        "Loss against wall time, " + problem.title + ".", curves(true)});
  }
};

}  // namespace time_reversal_case
}  // namespace

std::unique_ptr<Experiment> make_time_reversal() {
  return std::make_unique<time_reversal_case::TimeReversal>();
}

} // namespace physgrad::experiments
