#include "physgrad/learn/mapped_jacobian.hpp"

#include <cblas.h>

#include <string>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

Index checked_rows(const double* data, Index batch, Index outputs, Index cols) {
  if (batch < 0 || outputs < 0 || cols < 0) {
    throw Error("MappedJacobian: sizes must be ≥ 0, got batch " + std::to_string(batch) +
                ", outputs " + std::to_string(outputs) + ", cols " + std::to_string(cols));
  }
  if (data == nullptr && batch * outputs * cols != 0) throw Error("MappedJacobian: no data");
  return batch * outputs;
}

int blas_size(Index n) { return static_cast<int>(n); }

}  // namespace

MappedJacobian::MappedJacobian(const double* data, Index batch, Index outputs, Index cols)
    : batch_(batch),
      outputs_(outputs),
      transposed_(data, cols, checked_rows(data, batch, outputs, cols)) {}

Matrix MappedJacobian::gram() const {
  const Index r = rows();
  Matrix g = Matrix::Zero(r, r);
  if (r == 0 || cols() == 0) return g;
  // (Jᵀ)ᵀ Jᵀ, lower triangle, as power_pinv's Gram path reads it.
  cblas_dsyrk(CblasColMajor, CblasLower, CblasTrans, blas_size(r), blas_size(cols()), 1.0,
              transposed_.data(), blas_size(cols()), 0.0, g.data(), blas_size(r));
  return g;
}

Vector MappedJacobian::apply_transpose(const Vector& c) const { return transposed_ * c; }

Vector MappedJacobian::apply(const Vector& w) const { return transposed_.transpose() * w; }

Matrix MappedJacobian::materialize() const { return transposed_.transpose(); }

StackedJacobian::Normal MappedJacobian::normal(const Vector& g) const {
  Normal out{Matrix::Zero(cols(), cols()), transposed_ * g};
  out.matrix.selfadjointView<Eigen::Lower>().rankUpdate(transposed_);
  return out;
}

}  // namespace physgrad
