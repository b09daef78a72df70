#include "physgrad/nn/mean_matched_network.hpp"

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

// C·m for every column: each column minus its mean.
Matrix centred_columns(const Matrix& m) {
  return m.rowwise() - m.colwise().mean();
}

std::vector<Matrix> centred_each(const std::vector<Matrix>& matrices) {
  std::vector<Matrix> out;
  out.reserve(matrices.size());
  for (const Matrix& m : matrices) out.push_back(centred_columns(m));
  return out;
}

}  // namespace

MeanMatchedNetwork::MeanMatchedNetwork(std::unique_ptr<Network> inner) : inner_(std::move(inner)) {
  if (!inner_) throw Error("MeanMatchedNetwork: no network to wrap");
  if (inner_->input_dim() != inner_->output_dim()) {
    throw Error("MeanMatchedNetwork: '" + inner_->name() + "' has " +
                std::to_string(inner_->input_dim()) + " inputs and " +
                std::to_string(inner_->output_dim()) +
                " outputs; matching the output's mean to the input's needs one field of each");
  }
}

nlohmann::json MeanMatchedNetwork::describe() const {
  nlohmann::json out = inner_->describe();
  out["output_mean"] = "input";
  return out;
}

Matrix MeanMatchedNetwork::forward(const Matrix& x, NetworkCache& cache) const {
  Matrix y = inner_->forward(x, cache);
  y.rowwise() += x.colwise().mean() - y.colwise().mean();
  return y;
}

Vector MeanMatchedNetwork::backward(const NetworkCache& cache, const Matrix& gy) const {
  return inner_->backward(cache, centred_columns(gy));
}

void MeanMatchedNetwork::per_sample_gradients(const NetworkCache& cache, const Matrix& gy,
                                              StridedMatrixRef out) const {
  inner_->per_sample_gradients(cache, centred_columns(gy), out);
}

Matrix MeanMatchedNetwork::per_sample_gram(const NetworkCache& cache,
                                           const std::vector<Matrix>& cotangents) const {
  return inner_->per_sample_gram(cache, centred_each(cotangents));
}

Matrix MeanMatchedNetwork::per_sample_gram_columns(const NetworkCache& cache,
                                                   const std::vector<Matrix>& cotangents,
                                                   const std::vector<Index>& selected) const {
  return inner_->per_sample_gram_columns(cache, centred_each(cotangents), selected);
}

Matrix MeanMatchedNetwork::jvp(const NetworkCache& cache, Index batch, const Vector& v) const {
  return centred_columns(inner_->jvp(cache, batch, v));
}

std::vector<DenseLayerFactors> MeanMatchedNetwork::dense_layer_factors(
    const NetworkCache& cache, const std::vector<Matrix>& cotangents) const {
  return inner_->dense_layer_factors(cache, centred_each(cotangents));
}

}  // namespace physgrad
