#include "physgrad/nn/dense_layer_gram.hpp"

#include <cblas.h>

#include <string>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

blasint blas_dim(Index value) { return static_cast<blasint>(value); }

std::string shape(const Matrix& m) {
  return std::to_string(m.rows()) + "×" + std::to_string(m.cols());
}

}  // namespace

DenseLayerGram::DenseLayerGram(Index columns, Index batch)
    : columns_(columns),
      batch_(batch),
      gram_(Matrix::Zero(columns, columns)),
      // dsyrk writes only the lower triangle; the strict upper part stays 0, so the diagonal
      // blocks added below carry nothing but zeros above their diagonal.
      block_(Matrix::Zero(columns, columns)),
      inputs_(batch, batch) {
  const bool valid =
      columns >= 0 && batch >= 0 && (columns == 0 || (batch > 0 && columns % batch == 0));
  if (!valid) {
    throw Error("DenseLayerGram: " + std::to_string(columns) +
                " columns are not a multiple of a batch of " + std::to_string(batch));
  }
}

void DenseLayerGram::add(const Matrix& deltas, const Matrix& inputs, bool with_bias) {
  if (finished_) throw Error("DenseLayerGram::add: the sum was already taken by finish()");
  if (deltas.cols() != columns_ || inputs.cols() != batch_) {
    throw Error("DenseLayerGram::add: deltas " + shape(deltas) + " and inputs " + shape(inputs) +
                " do not fit " + std::to_string(columns_) + " columns of a batch of " +
                std::to_string(batch_));
  }
  if (columns_ == 0) return;
  cblas_dsyrk(CblasColMajor, CblasLower, CblasTrans, blas_dim(columns_), blas_dim(deltas.rows()),
              1.0, deltas.data(), blas_dim(deltas.rows()), 0.0, block_.data(), blas_dim(columns_));
  inputs_.noalias() = inputs.transpose() * inputs;  // a_i · a_j
  if (with_bias) inputs_.array() += 1.0;
  // Only the blocks on and below the diagonal; finish() mirrors them.
  const Index b = batch_, blocks = columns_ / batch_;
  for (Index kk = 0; kk < blocks; ++kk) {
    for (Index k = kk; k < blocks; ++k) {
      gram_.block(k * b, kk * b, b, b).array() +=
          block_.block(k * b, kk * b, b, b).array() * inputs_.array();
    }
  }
}

Matrix DenseLayerGram::finish() {
  if (finished_) throw Error("DenseLayerGram::finish: called twice");
  finished_ = true;
  gram_.triangularView<Eigen::StrictlyUpper>() = gram_.transpose();
  block_.resize(0, 0);
  return std::move(gram_);
}

}  // namespace physgrad
