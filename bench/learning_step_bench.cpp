// Micro-benchmarks of the learning step: stacked-Jacobian assembly (formed J vs the factored
// Gram matrix), the power-pseudo-inverse backends, the reference eigendecomposition, and whole
// steps of HIG / Gauss-Newton / Adam on the reference configurations.
#include <benchmark/benchmark.h>

#include <lapacke.h>

#include <algorithm>
#include <vector>

#include "physgrad/linalg/power_pinv.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/physics/coupled_oscillators.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "physgrad/physics/poisson.hpp"
#include "physgrad/threads.hpp"
#include "physgrad/train/trainer.hpp"

namespace {

using namespace physgrad;

// One reference configuration: network, physics, loss and one batch.
struct Case {
  std::unique_ptr<Simulator> physics;
  L2Loss loss{2.0};
  Mlp network;
  Dataset batch;

  Case(std::unique_ptr<Simulator> p, std::vector<Index> widths, Activation activation, Index b,
       bool context)
      : physics(std::move(p)), network(std::move(widths), activation) {
    network.initialize(1);
    const Index n_in = network.input_dim();
    batch.inputs = Matrix::Random(n_in, b).cwiseAbs();
    batch.targets = Matrix::Random(physics->output_dim(), b);
    if (context) batch.context = batch.inputs;
  }
  LearningProblem problem() const { return {physics.get(), &loss}; }
};

// 0: hig-toy (B 128), 1: oscillators paper (B 128), 2: poisson 8×8 (B 16); batch 0 = these.
Case make_case(int which, Index batch = 0) {
  switch (which) {
    case 0:
      return Case(std::make_unique<DiagonalScale>(Vector{{1.0, 0.01}}), {1, 7, 2},
                  Activation::kTanh, batch > 0 ? batch : 128, false);
    case 1:
      return Case(std::make_unique<CoupledOscillators>(OscillatorConfig::paper()),
                  {4, 20, 20, 20, 96}, Activation::kRelu, batch > 0 ? batch : 128, true);
    default:
      return Case(std::make_unique<Poisson>(8), {64, 64, 128, 64, 64}, Activation::kTanh,
                  batch > 0 ? batch : 16, false);
  }
}

const char* case_name(int which) {
  return which == 0 ? "hig_toy" : which == 1 ? "oscillators" : "poisson";
}

// J Jᵀ of a reference batch: range(1) = 0 forms J and then the rank-k update, 1 builds it from
// the network's layer factors without forming J.
void gram_matrix(benchmark::State& state) {
  const auto which = static_cast<int>(state.range(0));
  const bool factored = state.range(1) == 1;
  Case c = make_case(which);
  MlpCache cache;
  const BatchState batch = evaluate_batch(c.network, c.problem(), c.batch,
                                          UpdateNeed::kStackedJacobian, cache);
  for (auto _ : state) {
    Matrix gram;
    if (factored) {
      gram = batch.jacobian->gram();
    } else {
      const Matrix j = batch.jacobian->materialize();
      gram.setZero(j.rows(), j.rows());
      gram.selfadjointView<Eigen::Lower>().rankUpdate(j);
    }
    benchmark::DoNotOptimize(gram.data());
  }
  state.SetLabel(std::string(case_name(which)) + (factored ? " J J^T factored" : " J J^T formed"));
}

// The symmetric eigendecomposition of a B·m × B·m matrix alone: the step's irreducible part.
void reference_eigendecomposition(benchmark::State& state) {
  const auto n = static_cast<Index>(state.range(0));
  const Matrix a = Matrix::Random(n, n);
  const Matrix sym = a * a.transpose();
  Vector lambda(n);
  for (auto _ : state) {
    Matrix w = sym;
    LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'L', static_cast<lapack_int>(n), w.data(),
                   static_cast<lapack_int>(n), lambda.data());
    benchmark::DoNotOptimize(w.data());
  }
}

void power_pinv_backend(benchmark::State& state) {
  const auto rows = static_cast<Index>(state.range(0)), cols = static_cast<Index>(state.range(1));
  const auto backend = static_cast<PinvBackend>(state.range(2));
  const Matrix j = Matrix::Random(rows, cols);
  const Vector g = Vector::Random(rows);
  for (auto _ : state) {
    benchmark::DoNotOptimize(power_pinv_apply(j, g, {0.5, 1e-6, backend}).data());
  }
  state.SetLabel(to_string(backend));
}

// W f(Λ) Wᵀ g with f(λ) = λ^{−(1+κ)/2} over λ > rcond²·λ_max of the symmetric PSD `gram`, as the
// Gram path computes it: every eigenpair by dsyevd, or (subset) only those above a lower
// bound of the cutoff by dsyevr with a value range; λ_max is bounded below by the Rayleigh
// quotient of a few power steps, so no kept pair is missed. Returns the result; `rank` the
// number of kept pairs.
Vector eigen_product(const Matrix& gram, const Vector& g, double kappa, double rcond,
                     bool subset, Index& rank) {
  const auto n = static_cast<lapack_int>(gram.rows());
  Matrix w = gram;
  Vector lambda(n);
  Matrix vectors;
  lapack_int found = n;
  if (subset) {
    Index start = 0;
    double bound = gram.diagonal().maxCoeff(&start);
    Vector v = Vector::Unit(n, start);
    for (int step = 0; step < 4; ++step) {
      v = (gram * v).normalized();
      bound = std::max(bound, v.dot(gram * v));
    }
    vectors.resize(n, n);
    std::vector<lapack_int> support(2 * static_cast<std::size_t>(n));
    LAPACKE_dsyevr(LAPACK_COL_MAJOR, 'V', 'V', 'L', n, w.data(), n, rcond * rcond * bound,
                   2 * gram.trace() + 1, 0, 0, 0.0, &found, lambda.data(), vectors.data(), n,
                   support.data());
  } else {
    LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'L', n, w.data(), n, lambda.data());
  }
  const Matrix& basis = subset ? vectors : w;
  const Vector sigma = lambda.head(found).cwiseMax(0.0).cwiseSqrt();
  rank = (sigma.array() > rcond * sigma(found - 1)).count();
  const auto kept = basis.middleCols(found - rank, rank);
  Vector c = kept.transpose() * g;
  c.array() *= sigma.tail(rank).array().pow(-1 - kappa);
  return kept * c;
}

// The eigen part of the HIG Gram path on the Gram matrix of a reference configuration at batch
// range(1): range(2) = 0 all eigenpairs (dsyevd, what power_pinv uses), 1 only those above the
// cutoff (dsyevr with a value range). Counters: n, the kept rank, and the relative difference
// of the two results.
void eigen_route(benchmark::State& state) {
  const auto which = static_cast<int>(state.range(0));
  Case c = make_case(which, static_cast<Index>(state.range(1)));
  const bool subset = state.range(2) == 1;
  MlpCache cache;
  const BatchState batch = evaluate_batch(c.network, c.problem(), c.batch,
                                          UpdateNeed::kStackedJacobian, cache);
  const Matrix gram = batch.jacobian->gram();
  const Vector& g = batch.loss_gradient_y;
  const double rcond = which == 2 ? 1e-5 : 1e-6;  // the experiments' τ for HIG
  Index rank = 0, other_rank = 0;
  Vector result;
  for (auto _ : state) {
    result = eigen_product(gram, g, 0.5, rcond, subset, rank);
    benchmark::DoNotOptimize(result.data());
  }
  const Vector other = eigen_product(gram, g, 0.5, rcond, !subset, other_rank);
  state.counters["n"] = static_cast<double>(gram.rows());
  state.counters["rank"] = static_cast<double>(rank);
  state.counters["rel_diff"] = (result - other).norm() / other.norm();
  state.SetLabel(std::string(case_name(which)) + (subset ? " dsyevr above cutoff" : " dsyevd"));
}

void learning_step(benchmark::State& state) {
  Case c = make_case(static_cast<int>(state.range(0)));
  const std::string id = state.range(1) == 0 ? "adam" : state.range(1) == 1 ? "gn" : "hig";
  const auto update = make_learning_update(id);
  MlpCache cache;
  for (auto _ : state) {
    const BatchState batch = evaluate_batch(c.network, c.problem(), c.batch, update->need(), cache);
    const UpdateStep step = update->step(batch);
    benchmark::DoNotOptimize(step.delta.data());
  }
  state.SetLabel(std::string(case_name(static_cast<int>(state.range(0)))) + " " + id);
}

}  // namespace

BENCHMARK(gram_matrix)->ArgsProduct({{0, 1, 2}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK(reference_eigendecomposition)->Arg(256)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond);
BENCHMARK(power_pinv_backend)
    ->Args({512, 2956, static_cast<int>(PinvBackend::kSvd)})
    ->Args({512, 2956, static_cast<int>(PinvBackend::kGram)})
    ->Args({1024, 24896, static_cast<int>(PinvBackend::kGram)})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(eigen_route)
    ->ArgsProduct({{1}, {64, 128, 256}, {0, 1}})
    ->ArgsProduct({{2}, {4, 16}, {0, 1}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(learning_step)
    ->ArgsProduct({{0, 1, 2}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  physgrad::set_blas_threads(1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
