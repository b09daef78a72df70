// Micro-benchmarks of the learning step: stacked-Jacobian assembly (formed J vs the factored
// Gram matrix), the power-pseudo-inverse backends, the reference eigendecomposition, the
// eigenpairs-above-the-cutoff route, whole steps of Adam / Gauss-Newton / HIG / SIP on the
// reference configurations (built by the experiments' own setup code), and a size sweep of
// the HIG step over B·m and |θ|. bench_report turns the results into docs/performance.md.
#include <benchmark/benchmark.h>

#include <cblas.h>
#include <lapacke.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "physgrad/autodiff/dual.hpp"
#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/learn/hig.hpp"
#include "physgrad/threads.hpp"
#include "physgrad/train/trainer.hpp"
#include "registry.hpp"

namespace {

using namespace physgrad;
using experiments::ReferenceCase;

// The reference configurations: the experiment and the batch size.
struct CaseSpec {
  const char* experiment;
  Index batch;
  const char* label;
};

constexpr CaseSpec kCases[] = {
    {"hig-toy", 128, "hig_toy"},              // 0: J 256 × 30
    {"oscillators", 128, "oscillators"},      // 1: J 512 × 2956
    {"poisson", 16, "poisson"},               // 2: J 1024 × 24 896
    {"poisson", 64, "poisson_b64"},           // 3: J 4096 × 24 896 (the HIG paper's batch)
    {"quantum-dipole", 16, "quantum_dipole"},  // 4: J 448 × 9484
};

const CaseSpec& case_spec(std::int64_t which) { return kCases[static_cast<std::size_t>(which)]; }

ReferenceCase make_case(std::int64_t which, Index batch = 0) {
  const CaseSpec& spec = case_spec(which);
  return experiments::builtin_registry().reference(spec.experiment, batch > 0 ? batch : spec.batch);
}

const char* rule_id(std::int64_t rule) {
  static const char* const ids[] = {"adam", "gn", "hig", "sip"};
  return ids[rule];
}

// J Jᵀ (lower triangle) of J by dsyrk.
Matrix syrk_gram(const Matrix& j) {
  Matrix gram(j.rows(), j.rows());
  cblas_dsyrk(CblasColMajor, CblasLower, CblasNoTrans, static_cast<int>(j.rows()),
              static_cast<int>(j.cols()), 1.0, j.data(), static_cast<int>(j.rows()), 0.0,
              gram.data(), static_cast<int>(j.rows()));
  return gram;
}

// J Jᵀ of a reference batch: range(1) = 0 forms J and then the rank-k update (dsyrk), 1 builds
// it from the network's layer factors without forming J, 2 times the dsyrk on a formed J alone.
void gram_matrix(benchmark::State& state) {
  const std::int64_t route = state.range(1);
  ReferenceCase c = make_case(state.range(0));
  MlpCache cache;
  const BatchState batch = evaluate_batch(c.network, c.problem(), c.batch,
                                          UpdateNeed::kStackedJacobian, cache);
  const Matrix formed = route == 2 ? batch.jacobian->materialize() : Matrix();
  for (auto _ : state) {
    const Matrix gram = route == 1   ? batch.jacobian->gram()
                        : route == 2 ? syrk_gram(formed)
                                     : syrk_gram(batch.jacobian->materialize());
    benchmark::DoNotOptimize(gram.data());
  }
  state.counters["rows"] = static_cast<double>(batch.jacobian->rows());
  state.counters["cols"] = static_cast<double>(batch.jacobian->cols());
  state.SetLabel(std::string(case_spec(state.range(0)).label) +
                 (route == 1 ? " J J^T factored" : route == 2 ? " dsyrk on J" : " J J^T formed"));
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

// A symmetric positive semi-definite matrix G seen as the normal equations of power_pinv_apply:
// normal(g) = (G, g), so the normal path returns W f(Λ) Wᵀ g with f(λ) = λ^{−(1+κ)/2} over
// λ > rcond²·λ_max — the eigen part of the Gram path alone, on the library's own code.
class SymmetricOperator final : public JacobianOperator {
 public:
  explicit SymmetricOperator(const Matrix& g) : g_(&g) {}
  Index rows() const override { return g_->rows(); }
  Index cols() const override { return g_->cols(); }
  Matrix gram() const override { return *g_; }
  Vector apply_transpose(const Vector& c) const override { return c; }
  Matrix materialize() const override { return *g_; }
  Normal normal(const Vector& g) const override { return {*g_, g}; }

 private:
  const Matrix* g_;
};

// The eigensolve modes the benchmarks compare, by index: 0 dsyevd (all pairs), 1 dsyevr (pairs
// above the cutoff), 2 ssyevd, 3 ssyevr (the same in float), 4 auto precision and eigensolver,
// 5 dsytrd + QL rotations applied to the vector (the tridiagonal eigensolver), 6 ssytrd + QL.
struct EigensolveMode {
  PinvPrecision precision;
  PinvEigensolver eigensolver;
  const char* label;
};
constexpr EigensolveMode kEigensolveModes[] = {
    {PinvPrecision::kDouble, PinvEigensolver::kFull, "dsyevd"},
    {PinvPrecision::kDouble, PinvEigensolver::kSubset, "dsyevr above cutoff"},
    {PinvPrecision::kFloat, PinvEigensolver::kFull, "ssyevd"},
    {PinvPrecision::kFloat, PinvEigensolver::kSubset, "ssyevr above cutoff"},
    {PinvPrecision::kAuto, PinvEigensolver::kAuto, "auto"},
    {PinvPrecision::kDouble, PinvEigensolver::kTridiagonal, "dsytrd + QL"},
    {PinvPrecision::kFloat, PinvEigensolver::kTridiagonal, "ssytrd + QL"},
};

PowerPinvOptions eigensolve_options(std::int64_t mode, double kappa, double rcond) {
  const EigensolveMode& m = kEigensolveModes[mode];
  return {.kappa = kappa, .rcond = rcond, .precision = m.precision, .eigensolver = m.eigensolver};
}

const char* eigensolve_label(std::int64_t mode) { return kEigensolveModes[mode].label; }

Vector eigen_product(const Matrix& gram, const Vector& g, double kappa, double rcond,
                     std::int64_t mode, PowerPinvInfo* info = nullptr,
                     const PowerPinvInfo* previous = nullptr) {
  PowerPinvOptions options = eigensolve_options(mode, kappa, rcond);
  options.backend = PinvBackend::kNormal;
  options.previous = previous;
  return power_pinv_apply(SymmetricOperator(gram), g, options, info);
}

// The Gram matrix J Jᵀ of configuration `which` at `batch`, its g = ∂(mean L)/∂y and HIG's τ.
struct GramCase {
  Matrix gram;
  Vector g;
  double rcond;
};

GramCase gram_case(std::int64_t which, Index batch) {
  ReferenceCase c = make_case(which, batch);
  MlpCache cache;
  const BatchState state = evaluate_batch(c.network, c.problem(), c.batch,
                                          UpdateNeed::kStackedJacobian, cache);
  const double rcond =
      c.update("hig")->params().at("rcond").get<double>();
  return {state.jacobian->gram(), state.loss_gradient_y, rcond};
}

// The eigen part of the HIG Gram path on the Gram matrix of a reference configuration at batch
// range(1) in mode range(2) (kEigensolveModes; auto after one call that sets `previous`).
// Counters: n, the kept rank, σ_max/σ_min,kept, whether float resolves the spectrum, what auto
// ran (float 1; subset 1, tridiagonal 1), and rel_diff: the distance to the dsyevd result
// relative to it (for mode 0 that of dsyevr).
void eigen_route(benchmark::State& state) {
  const std::int64_t mode = state.range(2);
  const GramCase gc = gram_case(state.range(0), static_cast<Index>(state.range(1)));
  PowerPinvInfo info, previous;
  eigen_product(gc.gram, gc.g, 0.5, gc.rcond, 0, &previous);
  Vector result;
  for (auto _ : state) {
    result = eigen_product(gc.gram, gc.g, 0.5, gc.rcond, mode, &info, &previous);
    benchmark::DoNotOptimize(result.data());
  }
  const Vector other = eigen_product(gc.gram, gc.g, 0.5, gc.rcond, mode == 0 ? 1 : 0);
  state.counters["n"] = static_cast<double>(gc.gram.rows());
  state.counters["rank"] = static_cast<double>(info.rank);
  state.counters["kept_condition"] = kept_condition(info);
  state.counters["float_resolves"] = previous.float_resolves ? 1 : 0;
  state.counters["float"] = info.precision == PinvPrecision::kFloat ? 1 : 0;
  state.counters["subset"] = info.eigensolver == PinvEigensolver::kSubset ? 1 : 0;
  state.counters["tridiagonal"] = info.eigensolver == PinvEigensolver::kTridiagonal ? 1 : 0;
  state.counters["rel_diff"] = (result - other).norm() / other.norm();
  state.SetLabel(std::string(case_spec(state.range(0)).label) + " " + eigensolve_label(mode));
}

// An approximate f(G)·g with f(λ) = λ^{−(1+κ)/2}: k Lanczos steps from q₁ = g/‖g‖ (with full
// reorthogonalization) give G Q = Q T + residual with T tridiagonal, and f(G)·g ≈
// ‖g‖ Q f(T) e₁, where f is applied to the Ritz values above rcond² times the largest (0 below).
// Its error depends on how well k steps resolve the kept part of the spectrum.
Vector lanczos_product(const Matrix& gram, const Vector& g, double kappa, double rcond, Index k) {
  const Index n = gram.rows();
  k = std::min(k, n);
  Matrix q(n, k);
  Vector alpha = Vector::Zero(k), beta = Vector::Zero(k);
  q.col(0) = g / g.norm();
  Index steps = k;
  Vector w(n);
  for (Index j = 0; j < k; ++j) {
    w.noalias() = gram * q.col(j);
    alpha(j) = q.col(j).dot(w);
    for (int pass = 0; pass < 2; ++pass) {
      w -= q.leftCols(j + 1) * (q.leftCols(j + 1).transpose() * w);
    }
    if (j + 1 == k) break;
    beta(j) = w.norm();
    if (beta(j) <= 1e-14 * std::abs(alpha(0))) {
      steps = j + 1;
      break;
    }
    q.col(j + 1) = w / beta(j);
  }
  Matrix t = Matrix::Zero(steps, steps);
  t.diagonal() = alpha.head(steps);
  if (steps > 1) {
    t.diagonal(1) = beta.head(steps - 1);
    t.diagonal(-1) = beta.head(steps - 1);
  }
  const Eigen::SelfAdjointEigenSolver<Matrix> eig(t);
  const Vector& theta = eig.eigenvalues();
  const double cutoff = rcond * rcond * theta.maxCoeff();
  Vector coefficients(steps);
  for (Index i = 0; i < steps; ++i) {
    coefficients(i) =
        theta(i) > cutoff ? eig.eigenvectors()(0, i) * std::pow(theta(i), -0.5 * (1 + kappa)) : 0.0;
  }
  return g.norm() * (q.leftCols(steps) * (eig.eigenvectors() * coefficients));
}

// The Lanczos approximation with range(2) steps on the Gram matrix of configuration range(0)
// at batch range(1); counter rel_err: its relative distance to the dsyevd result.
void lanczos_route(benchmark::State& state) {
  const GramCase gc = gram_case(state.range(0), static_cast<Index>(state.range(1)));
  const Matrix& gram = gc.gram;
  const Vector& g = gc.g;
  const double rcond = gc.rcond;
  const auto k = static_cast<Index>(state.range(2));
  Vector result;
  for (auto _ : state) {
    result = lanczos_product(gram, g, 0.5, rcond, k);
    benchmark::DoNotOptimize(result.data());
  }
  const Vector exact = eigen_product(gram, g, 0.5, rcond, 0);
  state.counters["n"] = static_cast<double>(gram.rows());
  state.counters["k"] = static_cast<double>(k);
  state.counters["rel_err"] = (result - exact).norm() / exact.norm();
  state.SetLabel(std::string(case_spec(state.range(0)).label) + " Lanczos");
}

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
                    .kappa = params.at("kappa").get<double>(),
                    .rcond = params.at("rcond").get<double>(),
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

BENCHMARK(gram_matrix)->ArgsProduct({{0, 1, 4, 2, 3}, {1}})->Unit(benchmark::kMillisecond);
BENCHMARK(gram_matrix)->ArgsProduct({{0, 1, 4, 2}, {0, 2}})->Unit(benchmark::kMillisecond);
// J itself is 4096 × 24 896 (0.8 GB) here: one iteration.
BENCHMARK(gram_matrix)->ArgsProduct({{3}, {0, 2}})->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(reference_eigendecomposition)->Arg(256)->Arg(448)->Arg(512)->Arg(1024)
    ->Unit(benchmark::kMillisecond);
// About 8 s an iteration at 4096: two, averaged.
BENCHMARK(reference_eigendecomposition)->Arg(4096)->Iterations(2)->Unit(benchmark::kMillisecond);
BENCHMARK(power_pinv_backend)
    ->Args({512, 2956, static_cast<int>(PinvBackend::kSvd)})
    ->Args({512, 2956, static_cast<int>(PinvBackend::kGram)})
    ->Args({1024, 24896, static_cast<int>(PinvBackend::kGram)})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(eigen_route)
    ->ArgsProduct({{1}, {64, 128, 256}, {0, 1, 2, 3, 4, 5, 6}})
    ->ArgsProduct({{2}, {4, 16}, {0, 1, 2, 3, 4, 5, 6}})
    ->ArgsProduct({{4}, {16, 64}, {0, 1, 2, 3, 4, 5, 6}})
    ->Unit(benchmark::kMillisecond);
// n = 4096: seconds per call, one each.
BENCHMARK(eigen_route)
    ->ArgsProduct({{2}, {64}, {0, 1, 2, 3, 4, 5, 6}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(lanczos_route)
    ->ArgsProduct({{1}, {128}, {32, 128, 512}})
    ->ArgsProduct({{2}, {16}, {32, 128, 512}})
    ->ArgsProduct({{4}, {64}, {32, 128, 512}})
    ->Unit(benchmark::kMillisecond);
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

int main(int argc, char** argv) {
  physgrad::set_blas_threads(1);
  benchmark::AddCustomContext("blas_core", physgrad::blas_core());
  if (const std::string note = physgrad::blas_core_note(); !note.empty()) {
    std::fprintf(stderr, "%s\n", note.c_str());
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
