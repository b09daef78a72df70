#include "physgrad/physics/poisson.hpp"

#include <Eigen/SparseCholesky>
#include <cmath>
#include <sstream>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"

namespace physgrad {

struct Poisson::Factor {
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt;  // of −L (symmetric positive definite)
};

Poisson::Poisson(Index n) : n_(n) {
  if (n < 1) {
    std::ostringstream msg;
    msg << "poisson: grid size must be ≥ 1, got " << n;
    throw Error(msg.str());
  }
  // The assembly (5 entries a cell) and the Cholesky factor, whose fill grows like 6·log₂ n
  // entries a cell (measured up to n = 512: about 700 B a cell in all); in double, so an n
  // whose n² overflows Index is refused here too.
  const double cells = static_cast<double>(n) * static_cast<double>(n);
  require_memory(cells * (200 + 96 * std::log2(static_cast<double>(n) + 1)),
                 "poisson: " + std::to_string(n) + "×" + std::to_string(n) +
                     " grid (its Laplacian and Cholesky factor)");
  std::vector<Eigen::Triplet<double, Index>> entries;
  for (Index j = 0; j < n; ++j) {
    for (Index i = 0; i < n; ++i) {
      const Index k = i + n * j;
      entries.emplace_back(k, k, 4.0);
      if (i > 0) entries.emplace_back(k, k - 1, -1.0);
      if (i + 1 < n) entries.emplace_back(k, k + 1, -1.0);
      if (j > 0) entries.emplace_back(k, k - n, -1.0);
      if (j + 1 < n) entries.emplace_back(k, k + n, -1.0);
    }
  }
  Eigen::SparseMatrix<double> negative_laplacian(n * n, n * n);
  negative_laplacian.setFromTriplets(entries.begin(), entries.end());
  auto factor = std::make_shared<Factor>();
  factor->llt.compute(negative_laplacian);
  if (factor->llt.info() != Eigen::Success) throw Error("poisson: Cholesky factorisation failed");
  factor_ = std::move(factor);
}

Matrix Poisson::laplace(const Matrix& x) const {
  const Index n = n_;
  Matrix y(x.rows(), x.cols());
  for (Index b = 0; b < x.cols(); ++b) {
    const Eigen::Map<const Matrix> u(x.col(b).data(), n, n);  // u(i, j) = x(i + n·j)
    Eigen::Map<Matrix> v(y.col(b).data(), n, n);
    v = -4 * u;
    v.topRows(n - 1) += u.bottomRows(n - 1);
    v.bottomRows(n - 1) += u.topRows(n - 1);
    v.leftCols(n - 1) += u.rightCols(n - 1);
    v.rightCols(n - 1) += u.leftCols(n - 1);
  }
  return y;
}

Matrix Poisson::forward_batch(const Matrix& x, const Matrix& context) const {
  check_batch(x, context, "forward");
  return laplace(x);
}

Matrix Poisson::vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const {
  check_vjp_batch(x, context, gy);
  return laplace(gy);
}

Matrix Poisson::weighted_hessian(const Vector& x, const Vector& context,
                                 const Vector& /*w*/) const {
  check_batch(x, context, "weighted_hessian");
  return Matrix::Zero(x.size(), x.size());
}

Vector Poisson::inverse(const Vector& y, const Vector& x0, const Vector& context) const {
  check_batch(x0, context, "inverse");
  if (y.size() != output_dim()) {
    std::ostringstream msg;
    msg << name() << ".inverse: y has " << y.size() << " entries, expected " << output_dim();
    throw Error(msg.str());
  }
  return factor_->llt.solve(-y);
}

Matrix Poisson::solve_batch(const Matrix& y) const {
  if (y.rows() != output_dim()) {
    std::ostringstream msg;
    msg << name() << ".solve_batch: y has " << y.rows() << " rows, expected " << output_dim();
    throw Error(msg.str());
  }
  return factor_->llt.solve(-y);
}

}  // namespace physgrad
