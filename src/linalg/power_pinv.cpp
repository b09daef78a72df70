#include "physgrad/linalg/power_pinv.hpp"

#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {
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
  if (!all_finite(a) || !all_finite(g)) {
    throw Error(std::string(what) + ": non-finite entry in the matrix or vector");
  }
}
}  // namespace

Vector power_pinv_apply(const Matrix& j, const Vector& g, const PowerPinvOptions& options) {
  check_operands(j, g, "power_pinv_apply");
  check_rcond(options.rcond);
  if (!std::isfinite(options.kappa)) throw Error("power_pinv_apply: kappa must be finite");
  if (j.size() == 0) return Vector::Zero(j.cols());

  const Eigen::BDCSVD<Matrix> svd(j, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Vector& sigma = svd.singularValues();
  const double cutoff = options.rcond * sigma(0);
  Vector coefficients = svd.matrixU().transpose() * g;
  for (Index i = 0; i < sigma.size(); ++i) {
    coefficients(i) = sigma(i) > cutoff && sigma(i) > 0
                          ? coefficients(i) * std::pow(sigma(i), -options.kappa)
                          : 0.0;
  }
  return svd.matrixV() * coefficients;
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
