#include "physgrad/linalg/power_pinv.hpp"

#include <functional>

#include <cblas.h>
#include <lapacke.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

constexpr std::array<std::pair<PinvBackend, const char*>, 4> kBackendNames{{
    {PinvBackend::kAuto, "auto"},
    {PinvBackend::kSvd, "svd"},
    {PinvBackend::kGram, "gram"},
    {PinvBackend::kNormal, "normal"},
}};

void check_rcond(double rcond) {
  if (!(rcond >= 0 && rcond < 1)) {
    std::ostringstream msg;
    msg << "rcond must be in [0, 1), got " << rcond;
    throw Error(msg.str());
  }
}

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

lapack_int lapack_dim(Index n) {
  if (n > std::numeric_limits<lapack_int>::max()) {
    throw Error("power_pinv_apply: dimension " + std::to_string(n) + " too large for LAPACK");
  }
  return static_cast<lapack_int>(n);
}

void check_lapack(lapack_int status, const char* routine) {
  if (status != 0) {
    throw NumericalError(std::string("power_pinv_apply: LAPACK ") + routine + " failed (info = " +
                std::to_string(status) + ")");
  }
}

// Thin SVD J = U Σ Vᵀ by divide and conquer (dgesdd), then V Σ^{−κ} Uᵀ g over the kept σ, which
// are the leading ones (dgesdd sorts σ descending).
Vector svd_apply(const Matrix& j, const Vector& g, double kappa, PowerPinvInfo& info) {
  const lapack_int m = lapack_dim(j.rows());
  const lapack_int n = lapack_dim(j.cols());
  const lapack_int k = std::min(m, n);
  Matrix a = j;  // dgesdd overwrites its input
  Matrix u(m, k);
  Matrix vt(k, n);
  Vector sigma(k);
  check_lapack(LAPACKE_dgesdd(LAPACK_COL_MAJOR, 'S', m, n, a.data(), m, sigma.data(), u.data(), m,
                              vt.data(), k),
               "dgesdd");
  info.sigma_max = sigma(0);
  if (!std::isfinite(info.sigma_max)) {
    throw NumericalError("power_pinv_apply: the largest singular value of J overflows");
  }
  info.rank = (sigma.array() > info.rcond_used * info.sigma_max).count();
  Vector c = u.leftCols(info.rank).transpose() * g;
  c.array() *= sigma.head(info.rank).array().pow(-kappa);
  return vt.topRows(info.rank).transpose() * c;
}

// W Σ^{−1−κ} Wᵀ x for the symmetric w = W Σ² Wᵀ (lower triangle used, overwritten by dsyevd)
// over the kept σ, which are the trailing ones (dsyevd sorts ascending).
Vector eigen_apply(Matrix& w, const Vector& x, double kappa, PowerPinvInfo& info) {
  const lapack_int n = lapack_dim(w.rows());
  if (!all_finite(w) || !all_finite(x)) {
    throw NumericalError("power_pinv_apply: J Jᵀ, JᵀJ or Jᵀg overflows (non-finite entry)");
  }
  Vector lambda(n);
  check_lapack(LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'L', n, w.data(), n, lambda.data()),
               "dsyevd");
  const Vector sigma = lambda.cwiseMax(0.0).cwiseSqrt();  // rounding can leave λ slightly < 0
  info.sigma_max = sigma(n - 1);
  info.rank = (sigma.array() > info.rcond_used * info.sigma_max).count();
  Vector c = w.rightCols(info.rank).transpose() * x;
  c.array() *= sigma.tail(info.rank).array().pow(-1 - kappa);
  return w.rightCols(info.rank) * c;
}

// J Jᵀ (gram = true) or Jᵀ J by dsyrk, lower triangle.
Matrix squared(const Matrix& j, bool gram) {
  const lapack_int n = lapack_dim(gram ? j.rows() : j.cols());
  const lapack_int k = lapack_dim(gram ? j.cols() : j.rows());
  Matrix w(n, n);
  cblas_dsyrk(CblasColMajor, CblasLower, gram ? CblasNoTrans : CblasTrans, n, k, 1.0, j.data(),
              lapack_dim(j.rows()), 0.0, w.data(), n);
  return w;
}

void check_kappa(double kappa) {
  if (!std::isfinite(kappa)) {
    std::ostringstream msg;
    msg << "power_pinv_apply: kappa must be finite, got " << kappa;
    throw Error(msg.str());
  }
}

}  // namespace

std::string to_string(PinvBackend backend) {
  for (const auto& [value, name] : kBackendNames) {
    if (value == backend) return name;
  }
  throw Error("to_string: invalid PinvBackend value " +
              std::to_string(static_cast<int>(backend)));
}

PinvBackend parse_pinv_backend(const std::string& name) {
  std::string known;
  for (const auto& [value, candidate] : kBackendNames) {
    if (name == candidate) return value;
    known += known.empty() ? "" : ", ";
    known += candidate;
  }
  throw Error(std::string("unknown pinv backend '") + name + "' (known: " + known + ")");
}

PinvBackend resolve_pinv_backend(Index rows, Index cols, const PowerPinvOptions& options) {
  if (options.backend != PinvBackend::kAuto) return options.backend;
  return options.rcond < kMinGramRcond ? PinvBackend::kSvd
         : rows <= cols                ? PinvBackend::kGram
                                       : PinvBackend::kNormal;
}

Vector power_pinv_apply(const Matrix& j, const Vector& g, const PowerPinvOptions& options,
                        PowerPinvInfo* info) {
  check_operands(j, g, "power_pinv_apply");
  check_rcond(options.rcond);
  check_kappa(options.kappa);
  const PinvBackend backend = resolve_pinv_backend(j.rows(), j.cols(), options);
  if (backend == PinvBackend::kGram && j.size() != 0) {
    return power_pinv_apply_gram(
        squared(j, true), g, [&j](const Vector& c) { return Vector(j.transpose() * c); }, options,
        info);
  }

  PowerPinvInfo local;
  PowerPinvInfo& out = info != nullptr ? *info : local;
  out = {};
  out.backend = backend;
  out.rcond_used =
      out.backend == PinvBackend::kSvd ? options.rcond : std::max(options.rcond, kMinGramRcond);
  if (j.size() == 0) return Vector::Zero(j.cols());

  if (out.backend == PinvBackend::kNormal) {
    Matrix w = squared(j, false);
    return eigen_apply(w, j.transpose() * g, options.kappa, out);
  }
  return svd_apply(j, g, options.kappa, out);
}

namespace {

// Checks the operands of a symmetric path (a square matrix of g's size) and starts its info.
void start_symmetric(const Matrix& matrix, const Vector& g, const char* name,
                     PinvBackend backend, const PowerPinvOptions& options, PowerPinvInfo& out) {
  if (matrix.rows() != matrix.cols()) throw Error(std::string(name) + ": the matrix is not square");
  check_operands(matrix, g, name);
  check_rcond(options.rcond);
  check_kappa(options.kappa);
  out = {};
  out.backend = backend;
  out.rcond_used = std::max(options.rcond, kMinGramRcond);
}

}  // namespace

Vector power_pinv_apply_gram(Matrix gram, const Vector& g,
                             const std::function<Vector(const Vector&)>& apply_transpose,
                             const PowerPinvOptions& options, PowerPinvInfo* info) {
  PowerPinvInfo local;
  PowerPinvInfo& out = info != nullptr ? *info : local;
  start_symmetric(gram, g, "power_pinv_apply_gram", PinvBackend::kGram, options, out);
  if (gram.size() == 0) return apply_transpose(Vector::Zero(0));
  return apply_transpose(eigen_apply(gram, g, options.kappa, out));
}

Vector power_pinv_apply_normal(Matrix normal, const Vector& jt_g, const PowerPinvOptions& options,
                               PowerPinvInfo* info) {
  PowerPinvInfo local;
  PowerPinvInfo& out = info != nullptr ? *info : local;
  start_symmetric(normal, jt_g, "power_pinv_apply_normal", PinvBackend::kNormal, options, out);
  if (normal.size() == 0) return Vector::Zero(0);
  return eigen_apply(normal, jt_g, options.kappa, out);
}

Vector symmetric_pinv_apply(const Matrix& a, const Vector& g, double rcond) {
  check_operands(a, g, "symmetric_pinv_apply");
  check_rcond(rcond);
  if (a.rows() != a.cols()) throw Error("symmetric_pinv_apply: matrix is not square");
  if (a.size() == 0) return Vector::Zero(0);

  const Eigen::SelfAdjointEigenSolver<Matrix> eig(0.5 * (a + a.transpose()));
  const Vector& lambda = eig.eigenvalues();  // ascending
  const double cutoff = rcond * lambda.cwiseAbs().maxCoeff();
  Vector coefficients = eig.eigenvectors().transpose() * g;
  for (Index i = 0; i < lambda.size(); ++i) {
    coefficients(i) = std::abs(lambda(i)) > cutoff && lambda(i) != 0 ? coefficients(i) / lambda(i)
                                                                     : 0.0;
  }
  return eig.eigenvectors() * coefficients;
}

}  // namespace physgrad
