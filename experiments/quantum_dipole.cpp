// quantum-dipole: a network maps a target superposition of the 2nd and 3rd eigenstates to the
// 384 dipole controls that steer the ground state there (Crank-Nicolson Schrödinger solver,
// fidelity loss 1 − |⟨ψ*|ψ(T)⟩|²): Adam vs HIG (experiments.md E12).
#include <cmath>

#include "experiment_list.hpp"
#include "learning_runs.hpp"
#include "reference_case.hpp"
#include "physgrad/error.hpp"
#include "physgrad/loss/fidelity.hpp"
#include "physgrad/physics/quantum_dipole.hpp"
#include "sampling.hpp"

namespace physgrad::experiments {
namespace {

// Targets (c₁ψ₂ + c₂ψ₃)/√(c₁² + c₂²) with c ~ N(0, 1); every sample starts in ψ₁.
Dataset make_targets(Index n, Index points, std::uint64_t seed) {
  Sampler sampler(seed);
  const Vector psi1 = dipole_eigenstate(1, points), psi2 = dipole_eigenstate(2, points),
               psi3 = dipole_eigenstate(3, points);
  Dataset data{Matrix(psi1.size(), n), Matrix(), psi1.replicate(1, n)};
  for (Index i = 0; i < n; ++i) {
    const double c1 = sampler.normal(), c2 = sampler.normal();
    data.inputs.col(i) = (c1 * psi2 + c2 * psi3) / std::hypot(c1, c2);
  }
  data.targets = data.inputs;
  return data;
}

std::vector<Index> widths(const QuantumDipole& physics) {
  return {physics.output_dim(), 20, 20, 20, physics.input_dim()};
}

// The paper's setting with --steps.
QuantumDipoleConfig configuration(const Settings& settings) {
  QuantumDipoleConfig config = QuantumDipoleConfig::paper();
  config.steps = settings.integer("steps");
  return config;
}

Mlp make_network(const QuantumDipole& physics, std::uint64_t seed) {
  Mlp network(widths(physics), Activation::kTanh);
  network.initialize(seed);
  return network;
}

const std::map<std::string, RuleDefaults>& rule_defaults() {
  static const std::map<std::string, RuleDefaults> defaults = {
      {"adam", {{.lr = 5e-4}, 256}},
      {"sgd", {{.lr = 1e-2}, 256}},
      {"gn", {{.lr = 0.5, .rcond = 1e-5}, 16}},
      {"hig", {{.lr = 0.5, .rcond = 1e-5}, 16}}};
  return defaults;
}

class QuantumDipoleExperiment final : public Experiment {
 public:
  std::string name() const override { return "quantum-dipole"; }
  std::string description() const override {
    return "dipole controls that steer a 1-D quantum state to a target superposition: "
           "Adam vs HIG";
  }
  std::vector<OptionSpec> options() const override {
    // A sample: its target and start state, the states of its trajectory, and the network's
    // activations on it.
    const auto bytes_each = [](const Settings& settings) {
      const QuantumDipole physics(configuration(settings));
      const Index state = physics.output_dim();
      return sample_bytes(widths(physics), (3 + settings.integer("steps")) * state);
    };
    std::vector<OptionSpec> options = {
        sample_count_option("train-size", "1024", "training targets", "16", bytes_each),
        sample_count_option("test-size", "1024", "test targets", "8", bytes_each),
        integer_option("steps", "384", "Crank-Nicolson steps Nt (dt = 0.05)")
            .at_least(1)
            .at_most(1e5)
            .quick("8"),
    };
    for (OptionSpec& spec : learning_options("30")) options.push_back(std::move(spec));
    return options;
  }
  std::vector<std::string> optimizer_choices() const override {
    return rule_ids(RuleKind::kLearning);
  }
  std::vector<std::string> default_optimizers() const override { return {"adam", "hig"}; }
  long long default_iterations() const override { return 0; }

  void validate(const Settings& settings) const override {
    require_training_limit(settings, "quantum-dipole");
    for (const std::string& id : settings.texts("optimizers")) {
      if (id == "sip") throw Error("quantum-dipole: --optimizers sip needs an inverse simulator; "
                                   "this one has none");
    }
  }

  void run(const Settings& settings, RunContext& context) const override {
    const QuantumDipoleConfig config = configuration(settings);
    const QuantumDipole physics(config);
    const FidelityLoss fidelity;
    const LearningProblem problem{&physics, &fidelity};
    const auto seed = static_cast<std::uint64_t>(settings.integer("seed"));
    const Dataset train_set = make_targets(settings.integer("train-size"), config.points, 2 * seed);
    const Dataset test_set = make_targets(settings.integer("test-size"), config.points, 2 * seed + 1);

    LearningSweep sweep(settings, context, rule_defaults());
    for (const std::string& id : settings.texts("optimizers")) {
      Mlp network = make_network(physics, seed);
      sweep.run(id, "Nt=" + std::to_string(config.steps), {{"seed", seed}}, network, problem,
                train_set, &test_set);
    }
    const std::string tag = "Nt=" + std::to_string(config.steps);
    sweep.add_loss_figures(context, sweep.first_seed_runs(tag), tag, "dipole", true);
    sweep.add_tables();
    context.add_note(
        "Reference (experiments.md E12): with u = 0 the infidelity is exactly 1. The paper ran "
        "5400 s per method (Adam B 256 lr 5e-4; HIG B 16 lr 0.5 τ 1e-5) and stored no numbers.");
  }
};

}  // namespace

std::unique_ptr<Experiment> make_quantum_dipole() {
  return std::make_unique<QuantumDipoleExperiment>();
}

// The paper configuration (Nt 384).
ReferenceCase quantum_dipole_reference(Index batch, std::uint64_t seed) {
  const QuantumDipoleConfig config = QuantumDipoleConfig::paper();
  auto physics = std::make_shared<QuantumDipole>(config);
  Mlp network = make_network(*physics, seed);
  return {std::move(physics), std::make_shared<FidelityLoss>(), std::move(network),
          make_targets(batch, config.points, 2 * seed), rule_defaults()};
}

}  // namespace physgrad::experiments
