#include "physgrad/inversion/power_pinv.hpp"

#include <cblas.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <type_traits>
#include <utility>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/spectral_cut.hpp"
#include "physgrad/text.hpp"
#include "symmetric_spectrum.hpp"

namespace physgrad {

namespace {

using inversion_detail::check_lapack;
using inversion_detail::lambda_max_lower_bound;
using inversion_detail::lapack_dim;
using inversion_detail::solve_spectrum;
using inversion_detail::Spectrum;

constexpr NameTable<PinvBackend, 4> kBackendNames{{
    {PinvBackend::kAuto, "auto"},
    {PinvBackend::kSvd, "svd"},
    {PinvBackend::kGram, "gram"},
    {PinvBackend::kNormal, "normal"},
}};
constexpr NameTable<PinvPrecision, 3> kPrecisionNames{{
    {PinvPrecision::kAuto, "auto"},
    {PinvPrecision::kDouble, "double"},
    {PinvPrecision::kFloat, "float"},
}};
constexpr NameTable<PinvEigensolver, 4> kEigensolverNames{{
    {PinvEigensolver::kAuto, "auto"},
    {PinvEigensolver::kFull, "full"},
    {PinvEigensolver::kSubset, "subset"},
    {PinvEigensolver::kTridiagonal, "tridiagonal"},
}};

void check_operands(const Matrix& a, const Vector& g, const char* what) {
  if (a.rows() != g.size()) {
    std::ostringstream msg;
    msg << what << ": matrix has " << a.rows() << " rows but the vector has " << g.size()
        << " entries";
    throw Error(msg.str());
  }
  if (!all_finite(a)) throw NumericalError(std::string(what) + ": non-finite entry in the matrix");
  if (!all_finite(g)) throw NumericalError(std::string(what) + ": non-finite entry in the vector");
}

// Thin SVD J = U Σ Vᵀ by divide and conquer (dgesdd, which overwrites `a` = J), then V Σ^{−κ} Uᵀ g
// over the σ the cut keeps.
Vector svd_apply(Matrix& a, const Vector& g, const SpectralCut& cut, PowerPinvInfo& info) {
  const lapack_int m = lapack_dim(a.rows());
  const lapack_int n = lapack_dim(a.cols());
  const lapack_int k = std::min(m, n);
  Matrix u(m, k);
  Matrix vt(k, n);
  Vector sigma(k);
  check_lapack(LAPACKE_dgesdd(LAPACK_COL_MAJOR, 'S', m, n, a.data(), m, sigma.data(), u.data(), m,
                              vt.data(), k),
               "dgesdd");
  if (!std::isfinite(sigma(0))) {
    throw NumericalError("power_pinv_apply: the largest singular value of J overflows");
  }
  const CutSpectrum kept = cut_singular_values(cut, sigma);
  info.sigma_max = kept.sigma_max;
  info.rank = kept.kept;
  info.sigma_min_kept = kept.sigma_min_kept;
  // dgesdd sorts σ descending: the kept ones lead.
  Vector c = u.leftCols(info.rank).transpose() * g;
  c.array() *= kept.weights.head(info.rank).array();
  return vt.topRows(info.rank).transpose() * c;
}

// The precision and eigensolver `options` ask for on an n × n matrix.
PinvEigensolver chosen_eigensolver(const PowerPinvOptions& options, Index n) {
  if (options.eigensolver != PinvEigensolver::kAuto) return options.eigensolver;
  const bool few_kept = options.previous != nullptr &&
                        static_cast<double>(options.previous->rank) <=
                            kSubsetKeptFraction * static_cast<double>(n);
  return few_kept ? PinvEigensolver::kSubset : PinvEigensolver::kTridiagonal;
}
bool tries_float(const PowerPinvOptions& options) {
  if (options.precision != PinvPrecision::kAuto) return options.precision == PinvPrecision::kFloat;
  return options.previous == nullptr || options.previous->float_resolves;
}

// W Σ^{−1−κ} Wᵀ x for the symmetric w = W Σ² Wᵀ (lower triangle used, consumed) over the σ the
// cut keeps.
Vector eigen_apply(Matrix& w, const Vector& x, const SpectralCut& cut,
                   const PowerPinvOptions& options, PowerPinvInfo& info) {
  if (!all_finite(w) || !all_finite(x)) {
    throw NumericalError("power_pinv_apply: J Jᵀ, JᵀJ or Jᵀg overflows (non-finite entry)");
  }
  const Index n = w.rows();
  const PinvEigensolver eigensolver = chosen_eigensolver(options, n);
  // Below a lower bound of the cut on λ, with room to spare: the pairs dsyevr finds include every
  // kept one.
  const double vl = eigensolver == PinvEigensolver::kSubset
                        ? 0.5 * cut.lambda_cut(lambda_max_lower_bound(w))
                        : 0.0;
  std::optional<Spectrum> spectrum;
  if (tries_float(options)) {
    spectrum = solve_spectrum<float>(w, eigensolver, vl, cut);
    if (options.precision == PinvPrecision::kAuto && !spectrum->float_resolves) {
      info.float_rejected = true;
      spectrum.reset();
    }
  }
  if (!spectrum) spectrum = solve_spectrum<double>(w, eigensolver, vl, cut);
  info.precision = spectrum->precision;
  info.eigensolver = spectrum->eigensolver;
  info.float_resolves = spectrum->float_resolves;
  if (spectrum->lambda.size() == 0) return Vector::Zero(n);  // λ_max = 0: nothing above the cut
  const CutSpectrum kept = cut_squared(cut, spectrum->lambda);
  info.sigma_max = kept.sigma_max;
  info.rank = kept.kept;
  info.sigma_min_kept = kept.sigma_min_kept;
  if (info.rank == 0) return Vector::Zero(n);
  return spectrum->apply(kept.weights, x);
}

// A Aᵀ (gram = true) or Aᵀ A by dsyrk: the lower triangle, the upper left zero.
Matrix squared(const Matrix& a, bool gram) {
  const lapack_int n = lapack_dim(gram ? a.rows() : a.cols());
  const lapack_int k = lapack_dim(gram ? a.cols() : a.rows());
  Matrix w = Matrix::Zero(n, n);
  if (a.size() != 0) {
    cblas_dsyrk(CblasColMajor, CblasLower, gram ? CblasNoTrans : CblasTrans, n, k, 1.0, a.data(),
                lapack_dim(a.rows()), 0.0, w.data(), n);
  }
  return w;
}

// work(), with its duration added to `seconds`.
template <typename Work>
auto timed(double& seconds, const Work& work) {
  const auto start = std::chrono::steady_clock::now();
  auto result = work();
  seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

void check_square(const Matrix& w, const char* form) {
  if (w.rows() != w.cols()) {
    throw Error(std::string("power_pinv_apply: the operator's ") + form + " is " +
                std::to_string(w.rows()) + "×" + std::to_string(w.cols()) + ", not square");
  }
}

}  // namespace

std::string to_string(PinvBackend backend) {
  return name_of(kBackendNames, backend, "PinvBackend");
}

PinvBackend parse_pinv_backend(const std::string& name) {
  return value_named(kBackendNames, name, "pinv backend");
}

std::string to_string(PinvPrecision precision) {
  return name_of(kPrecisionNames, precision, "PinvPrecision");
}

PinvPrecision parse_pinv_precision(const std::string& name) {
  return value_named(kPrecisionNames, name, "pinv precision");
}

std::string to_string(PinvEigensolver eigensolver) {
  return name_of(kEigensolverNames, eigensolver, "PinvEigensolver");
}

PinvEigensolver parse_pinv_eigensolver(const std::string& name) {
  return value_named(kEigensolverNames, name, "pinv eigensolver");
}

double kept_condition(const PowerPinvInfo& info) {
  CutSpectrum kept;
  kept.kept = info.rank;
  kept.sigma_max = info.sigma_max;
  kept.sigma_min_kept = info.sigma_min_kept;
  return kept.condition();
}

SpectralCut pinv_cut(PinvBackend backend, const PowerPinvOptions& options) {
  SpectralCut cut = options.cut;
  if (backend != PinvBackend::kSvd) cut.floor = std::max(cut.floor, kMinGramRcond);
  return cut;
}

bool float_resolves_spectrum(const Vector& lambda, Index n, const SpectralCut& cut) {
  if (lambda.size() == 0) return true;
  return inversion_detail::FloatBounds(n, lambda.maxCoeff(), cut)
      .resolves(lambda);
}

PinvBackend resolve_pinv_backend(Index rows, Index cols, const PowerPinvOptions& options) {
  if (options.backend != PinvBackend::kAuto) return options.backend;
  return options.cut.cutoff() < kMinGramRcond ? PinvBackend::kSvd
         : rows <= cols                ? PinvBackend::kGram
                                       : PinvBackend::kNormal;
}

Matrix DenseJacobian::gram() const { return squared(*j_, true); }

Vector DenseJacobian::apply_transpose(const Vector& c) const { return j_->transpose() * c; }

JacobianOperator::Normal DenseJacobian::normal(const Vector& g) const {
  return {squared(*j_, false), j_->transpose() * g};
}

// The one path choice: every path of J^{−κ} g starts here.
Vector power_pinv_apply(const JacobianOperator& j, const Vector& g,
                        const PowerPinvOptions& options, PowerPinvInfo* info,
                        PowerPinvTiming* timing) {
  if (j.rows() != g.size()) {
    throw Error("power_pinv_apply: J has " + std::to_string(j.rows()) +
                " rows but the vector has " + std::to_string(g.size()) + " entries");
  }
  if (!all_finite(g)) throw NumericalError("power_pinv_apply: non-finite entry in the vector");
  options.cut.check("power_pinv_apply");
  if (options.cut.damping != 0) {
    std::ostringstream msg;
    msg << "power_pinv_apply: damping must be 0 (J^{−κ} is undamped), got " << options.cut.damping;
    throw Error(msg.str());
  }
  PowerPinvInfo local_info;
  PowerPinvInfo& out = info != nullptr ? *info : local_info;
  PowerPinvTiming local_timing;
  PowerPinvTiming& time = timing != nullptr ? *timing : local_timing;
  out = {};
  out.backend = resolve_pinv_backend(j.rows(), j.cols(), options);
  const SpectralCut cut = pinv_cut(out.backend, options);
  out.rcond_used = cut.cutoff();
  if (j.rows() == 0 || j.cols() == 0) return Vector::Zero(j.cols());

  switch (out.backend) {
    case PinvBackend::kGram: {
      if (std::optional<Vector> shared = j.shared_gram_apply(g, options, info, &time)) {
        return std::move(*shared);
      }
      Matrix gram = timed(time.forming_seconds, [&] { return j.gram(); });
      check_square(gram, "J Jᵀ");
      return timed(time.inversion_seconds, [&] {
        return j.apply_transpose(eigen_apply(gram, g, cut, options, out));
      });
    }
    case PinvBackend::kNormal: {
      JacobianOperator::Normal normal = timed(time.forming_seconds, [&] { return j.normal(g); });
      check_square(normal.matrix, "JᵀJ");
      return timed(time.inversion_seconds,
                   [&] { return eigen_apply(normal.matrix, normal.rhs, cut, options, out); });
    }
    default: {
      Matrix formed = timed(time.forming_seconds, [&] { return j.materialize(); });
      check_operands(formed, g, "power_pinv_apply");
      return timed(time.inversion_seconds,
                   [&] { return svd_apply(formed, g, cut, out); });
    }
  }
}

Vector power_pinv_apply(const Matrix& j, const Vector& g, const PowerPinvOptions& options,
                        PowerPinvInfo* info) {
  check_operands(j, g, "power_pinv_apply");
  return power_pinv_apply(DenseJacobian(j), g, options, info);
}

Vector symmetric_pinv_apply(const Matrix& a, const Vector& g, const SpectralCut& cut) {
  check_operands(a, g, "symmetric_pinv_apply");
  cut.check("symmetric_pinv_apply");
  if (a.rows() != a.cols()) throw Error("symmetric_pinv_apply: matrix is not square");
  if (a.size() == 0) return Vector::Zero(0);

  const Eigen::SelfAdjointEigenSolver<Matrix> eig(0.5 * (a + a.transpose()));
  Vector coefficients = eig.eigenvectors().transpose() * g;
  cut_symmetric(cut, eig.eigenvalues(), coefficients);
  return eig.eigenvectors() * coefficients;
}

}  // namespace physgrad
