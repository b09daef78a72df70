#include "physgrad/nn/dense_layer_gram.hpp"

#include <cblas.h>

#include <string>
#include <utility>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

blasint blas_dim(Index value) { return static_cast<blasint>(value); }

std::string matrix_shape(const Matrix& m) {
  return std::to_string(m.rows()) + "×" + std::to_string(m.cols());
}

// `columns`, after checking that it is a multiple of `batch`.
Index checked_columns(Index columns, Index batch) {
  const bool valid =
      columns >= 0 && batch >= 0 && (columns == 0 || (batch > 0 && columns % batch == 0));
  if (!valid) {
    throw Error("DenseLayerGram: " + std::to_string(columns) +
                " columns are not a multiple of a batch of " + std::to_string(batch));
  }
  return columns;
}

}  // namespace

DenseLayerGram::DenseLayerGram(Index columns, Index batch)
    : columns_(checked_columns(columns, batch)),
      batch_(batch),
      gram_(Matrix::Zero(columns, columns)),
      // dsyrk writes only the lower triangle; the strict upper part stays 0, so the diagonal
      // blocks added below carry nothing but zeros above their diagonal.
      block_(Matrix::Zero(columns, columns)),
      inputs_(batch, batch) {}

DenseLayerGram::DenseLayerGram(Index columns, Index batch, std::vector<Index> selected)
    : columns_(checked_columns(columns, batch)),
      batch_(batch),
      selected_(std::move(selected)),
      all_(false),
      gram_(Matrix::Zero(columns, static_cast<Index>(selected_.size()))),
      inputs_(batch, batch) {
  for (const Index c : selected_) {
    if (c < 0 || c >= columns) {
      throw Error("DenseLayerGram: selected column " + std::to_string(c) + " outside [0, " +
                  std::to_string(columns) + ")");
    }
  }
}

void DenseLayerGram::add(const Matrix& deltas, const Matrix& inputs, bool with_bias) {
  if (finished_) throw Error("DenseLayerGram::add: the sum was already taken by finish()");
  if (deltas.cols() != columns_ || inputs.cols() != batch_) {
    throw Error("DenseLayerGram::add: deltas " + matrix_shape(deltas) + " and inputs " + matrix_shape(inputs) +
                " do not fit " + std::to_string(columns_) + " columns of a batch of " +
                std::to_string(batch_));
  }
  if (columns_ == 0) return;
  inputs_.noalias() = inputs.transpose() * inputs;  // a_i · a_j
  if (with_bias) inputs_.array() += 1.0;
  if (!all_) {
    add_selected(deltas);
    return;
  }
  cblas_dsyrk(CblasColMajor, CblasLower, CblasTrans, blas_dim(columns_), blas_dim(deltas.rows()),
              1.0, deltas.data(), blas_dim(deltas.rows()), 0.0, block_.data(), blas_dim(columns_));
  // Only the blocks on and below the diagonal; finish() mirrors them.
  const Index b = batch_, blocks = columns_ / batch_;
  for (Index kk = 0; kk < blocks; ++kk) {
    for (Index k = kk; k < blocks; ++k) {
      gram_.block(k * b, kk * b, b, b).array() +=
          block_.block(k * b, kk * b, b, b).array() * inputs_.array();
    }
  }
}

void DenseLayerGram::add_selected(const Matrix& deltas) {
  const auto count = static_cast<Index>(selected_.size());
  if (count == 0) return;
  Matrix chosen(deltas.rows(), count);  // D[:, S]
  for (Index s = 0; s < count; ++s) chosen.col(s) = deltas.col(selected_[static_cast<std::size_t>(s)]);
  block_.resize(columns_, count);
  cblas_dgemm(CblasColMajor, CblasTrans, CblasNoTrans, blas_dim(columns_), blas_dim(count),
              blas_dim(deltas.rows()), 1.0, deltas.data(), blas_dim(deltas.rows()), chosen.data(),
              blas_dim(deltas.rows()), 0.0, block_.data(), blas_dim(columns_));
  // Column s belongs to sample S_s mod B; row k·B + i to sample i.
  const Index b = batch_, blocks = columns_ / batch_;
  for (Index s = 0; s < count; ++s) {
    const auto a = inputs_.col(selected_[static_cast<std::size_t>(s)] % b).array();
    for (Index k = 0; k < blocks; ++k) {
      gram_.col(s).segment(k * b, b).array() += block_.col(s).segment(k * b, b).array() * a;
    }
  }
}

Matrix DenseLayerGram::finish() {
  if (finished_) throw Error("DenseLayerGram::finish: called twice");
  finished_ = true;
  if (all_) gram_.triangularView<Eigen::StrictlyUpper>() = gram_.transpose();
  block_.resize(0, 0);
  return std::move(gram_);
}

}  // namespace physgrad
