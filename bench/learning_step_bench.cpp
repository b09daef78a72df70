// Micro-benchmarks of whole learning steps: Adam / Gauss-Newton / HIG / SIP on the reference
// configurations (built by the experiments' own setup code), HIG by eigensolve mode, on a
// dual-number simulator and on threads, and a size sweep of the HIG step over B·m and |θ|.
// bench_report turns the results into docs/performance.md; eigen_route_bench.cpp holds the
// linear algebra alone.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "physgrad/autodiff/dual.hpp"
#include "physgrad/learn/hig.hpp"
#include "physgrad/threads.hpp"
#include "physgrad/train/trainer.hpp"
#include "reference_cases.hpp"
#include "single_thread_main.hpp"

namespace {

using namespace physgrad;
using namespace physgrad::bench;

// Whole train_step() calls of `update` on `c` (evaluate the batch, compute and apply Δθ); the
// counters give J's shape and, for Gauss-Newton and HIG, the backend (0 svd, 1 gram, 2 normal)
// and the kept rank.
void time_steps(benchmark::State& state, ReferenceCase& c, LearningUpdate& update) {
  StepState step_state;
  for (auto _ : state) {
    const StepReport report = train_step(c.network, update, c.problem(), c.batch, step_state);
    if (!report.applied()) {
      state.SkipWithError(describe_failure(report, 0).c_str());
      break;
    }
  }
  state.counters["rows"] = static_cast<double>(c.batch.size() * c.physics->output_dim());
  state.counters["cols"] = static_cast<double>(c.network.num_parameters());
  if (const auto* inverse = dynamic_cast<const HigUpdate*>(&update)) {
    const PinvBackend backend = inverse->last_info().backend;
    state.counters["backend"] = backend == PinvBackend::kSvd ? 0 : backend == PinvBackend::kGram ? 1 : 2;
    state.counters["rank"] = static_cast<double>(inverse->last_info().rank);
  }
}

// A whole step of rule range(1) (0 adam, 1 gn, 2 hig, 3 sip) on configuration range(0), with
// the experiment's step size and τ for the rule.
void learning_step(benchmark::State& state) {
  ReferenceCase c = make_case(state.range(0));
  const std::string id = rule_id(state.range(1));
  const auto update = c.update(id);
  time_steps(state, c, *update);
  state.SetLabel(std::string(case_spec(state.range(0)).label) + " " + id);
}

// The HIG step on configuration range(0) with the eigensolve of mode range(1)
// (kEigensolveModes); auto modes follow the previous step, as in training. Counters as
// time_steps() plus what ran (float 1 / double 0; subset 1, tridiagonal 1) and σ_max/σ_min,kept.
void learning_step_precision(benchmark::State& state) {
  ReferenceCase c = make_case(state.range(0));
  const nlohmann::json params = c.update("hig")->params();
  const PowerPinvOptions options = eigensolve_options(state.range(1), 0.5, 0.0);
  HigUpdate update({.lr = params.at("lr").get<double>(),
                    .cut = {.kappa = params.at("kappa").get<double>(),
                            .rcond = params.at("rcond").get<double>()},
                    .precision = options.precision,
                    .eigensolver = options.eigensolver});
  time_steps(state, c, update);
  state.counters["float"] = update.last_info().precision == PinvPrecision::kFloat ? 1 : 0;
  state.counters["subset"] = update.last_info().eigensolver == PinvEigensolver::kSubset ? 1 : 0;
  state.counters["tridiagonal"] =
      update.last_info().eigensolver == PinvEigensolver::kTridiagonal ? 1 : 0;
  state.counters["kept_condition"] = kept_condition(update.last_info());
  state.SetLabel(std::string(case_spec(state.range(0)).label) + " hig " +
                 eigensolve_label(state.range(1)));
}

// A chain of q unit masses with cubic springs, x = the initial displacements (velocities 0),
// y = the displacements after 30 explicit steps: n = m = q, written once over its scalar type.
struct CubicChain {
  template <typename T>
  Eigen::Matrix<T, Eigen::Dynamic, 1> operator()(const Eigen::Matrix<T, Eigen::Dynamic, 1>& x,
                                                 const Vector& /*context*/) const {
    const Index q = x.size();
    Eigen::Matrix<T, Eigen::Dynamic, 1> u = x, v = Eigen::Matrix<T, Eigen::Dynamic, 1>::Zero(q);
    const double dt = 0.05;
    for (int step = 0; step < 30; ++step) {
      for (Index i = 0; i < q; ++i) {
        const T left = i > 0 ? u(i - 1) : T(0.0), right = i + 1 < q ? u(i + 1) : T(0.0);
        const T a = left - u(i), b = right - u(i);
        v(i) += dt * (a + b + 0.5 * (a * a * a + b * b * b));
      }
      u += dt * v;
    }
    return u;
  }
};

// The chain as the library saw it before has_jacobian(): the stacked Jacobian makes m VJPs.
class ChainThroughVjps final : public AutoDiffSimulator<CubicChain> {
 public:
  using AutoDiffSimulator::AutoDiffSimulator;
  bool has_jacobian() const override { return false; }
};

// The HIG step on a forward-mode (dual number) simulator, the 16-mass cubic chain behind a
// 16-64-16 tanh network, batch 32: range(0) = 0 its Jacobian from jacobian() once per sample,
// 1 from m = 16 batched VJPs (each a dual Jacobian per sample, as AutoDiffSimulator's VJP is).
void autodiff_step(benchmark::State& state) {
  constexpr Index kMasses = 16, kBatch = 32;
  const AutoDiffSimulator<CubicChain> chain(CubicChain{}, "cubic_chain", kMasses, kMasses);
  const ChainThroughVjps through_vjps(CubicChain{}, "cubic_chain", kMasses, kMasses);
  const Simulator& physics = state.range(0) == 0 ? static_cast<const Simulator&>(chain)
                                                 : through_vjps;
  const L2Loss loss;
  const LearningProblem problem{&physics, &loss};
  Mlp network({kMasses, 64, kMasses}, Activation::kTanh);
  network.initialize(1);
  Dataset batch;
  batch.inputs = 0.3 * Matrix::Random(kMasses, kBatch);
  batch.targets = chain.forward_batch(0.2 * Matrix::Random(kMasses, kBatch), Matrix());
  HigUpdate update({.lr = 0.1});
  StepState step_state;
  double derivative_seconds = 0;
  for (auto _ : state) {
    const StepReport report = train_step(network, update, problem, batch, step_state);
    if (!report.applied()) {
      state.SkipWithError(describe_failure(report, 0).c_str());
      break;
    }
    derivative_seconds += report.derivative_seconds;
  }
  state.counters["derivative_ms"] =
      1e3 * derivative_seconds / static_cast<double>(std::max<std::int64_t>(1, state.iterations()));
  state.SetLabel(state.range(0) == 0 ? "cubic chain hig, jacobian() per sample"
                                     : "cubic chain hig, m VJPs");
}

// The HIG step on configuration range(0) with the m physics VJPs on range(1) threads.
void learning_step_threads(benchmark::State& state) {
  ReferenceCase c = make_case(state.range(0));
  const auto update = c.update("hig");
  set_jacobian_threads(static_cast<int>(state.range(1)));
  time_steps(state, c, *update);
  set_jacobian_threads(1);
  state.SetLabel(std::string(case_spec(state.range(0)).label) + " hig, VJP threads " +
                 std::to_string(state.range(1)));
}

// The HIG step on the Poisson problem with batch range(0) (B·m = 64·B) and a
// 64-h-2h-h-64 tanh network with h = range(1) (|θ| = 4h² + 132h + 64): how the step grows
// with B·m and |θ|, and where the backend switches (normal path when B·m > |θ|).
void size_sweep(benchmark::State& state) {
  ReferenceCase c =
      experiments::builtin_registry().reference("poisson", static_cast<Index>(state.range(0)));
  const auto h = static_cast<Index>(state.range(1));
  c.network = Mlp({64, h, 2 * h, h, 64}, Activation::kTanh);
  c.network.initialize(0);
  const auto update = c.update("hig");
  time_steps(state, c, *update);
}

}  // namespace

BENCHMARK(learning_step)
    ->ArgsProduct({{0, 2}, {0, 1, 2, 3}})
    ->ArgsProduct({{1, 4}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(learning_step)->Args({3, 2})->Iterations(2)->Unit(benchmark::kMillisecond);
BENCHMARK(learning_step_precision)
    ->ArgsProduct({{1, 2}, {0, 1, 2, 3, 4, 5, 6}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(learning_step_precision)
    ->ArgsProduct({{3}, {0, 2, 4, 5, 6}})
    ->Iterations(2)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(autodiff_step)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
// Wall time: the CPU time of the main thread alone would hide the workers.
BENCHMARK(learning_step_threads)
    ->ArgsProduct({{1, 4}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(size_sweep)
    ->ArgsProduct({{1, 4, 16}, {8, 32, 128}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(size_sweep)->ArgsProduct({{64}, {8, 32, 128}})->Iterations(1)->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) { return physgrad::bench::run_single_thread_benchmarks(argc, argv); }
