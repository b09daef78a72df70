// Micro-benchmarks of the linear algebra in the HIG step: stacked-Jacobian assembly (formed J vs
// the factored Gram matrix J Jᵀ), the power-pseudo-inverse backends, the reference
// eigendecomposition, the eigenpairs-above-the-cutoff route and its Lanczos approximation.
// bench_report turns the results into docs/performance.md.
#include <benchmark/benchmark.h>

#include <cblas.h>
#include <lapacke.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/learn/hig.hpp"
#include "physgrad/train/trainer.hpp"
#include "reference_cases.hpp"

namespace {

using namespace physgrad;
using namespace physgrad::bench;

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
    benchmark::DoNotOptimize(
        power_pinv_apply(j, g, {.cut = {.kappa = 0.5, .rcond = 1e-6}, .backend = backend}).data());
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
