#include "physgrad/nn/checked_network.hpp"

#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

// Reads one dimension of `inner`, which must be ≥ 1.
Index network_dim(const Network& inner, Index value, const char* what) {
  if (value < 1) {
    std::ostringstream msg;
    msg << "network '" << inner.name() << "': " << what << "() returned " << value
        << ", expected ≥ 1";
    throw Error(msg.str());
  }
  return value;
}

}  // namespace

CheckedNetwork::CheckedNetwork(const Network& inner)
    : inner_(&inner),
      input_dim_(network_dim(inner, inner.input_dim(), "input_dim")),
      output_dim_(network_dim(inner, inner.output_dim(), "output_dim")),
      parameters_(network_dim(inner, inner.num_parameters(), "num_parameters")) {
  const Index size = inner.parameters().size();
  if (size != parameters_) {
    std::ostringstream msg;
    msg << "network '" << inner.name() << "': parameters() has " << size
        << " entries, num_parameters() says " << parameters_;
    throw Error(msg.str());
  }
}

const CheckedNetwork& CheckedNetwork::around(const Network& network,
                                             std::optional<CheckedNetwork>& local) {
  if (const auto* checked = dynamic_cast<const CheckedNetwork*>(&network)) return *checked;
  return local.emplace(network);
}

Vector& CheckedNetwork::parameters() {
  throw Error("network '" + name() + "': its checked view is read-only");
}

void CheckedNetwork::check_result(const char* method, const Matrix& result, Index rows,
                                  Index cols) const {
  if (result.rows() == rows && result.cols() == cols) return;
  throw_wrong_result("network '" + name() + "'", method, result.rows(), result.cols(), rows, cols);
}

void CheckedNetwork::check_result(const char* method, const Vector& result, Index size) const {
  if (result.size() == size) return;
  throw_wrong_result("network '" + name() + "'", method, result.size(), -1, size, -1);
}

std::unique_ptr<NetworkCache> CheckedNetwork::new_cache() const {
  std::unique_ptr<NetworkCache> cache = inner_->new_cache();
  if (!cache) throw Error("network '" + name() + "': new_cache returned no cache");
  return cache;
}

Matrix CheckedNetwork::forward(const Matrix& x, NetworkCache& cache) const {
  Matrix out = inner_->forward(x, cache);
  check_result("forward", out, output_dim_, x.cols());
  return out;
}

Matrix CheckedNetwork::forward(const Matrix& x) const {
  Matrix out = inner_->forward(x);
  check_result("forward", out, output_dim_, x.cols());
  return out;
}

Vector CheckedNetwork::backward(const NetworkCache& cache, const Matrix& gy) const {
  Vector g = inner_->backward(cache, gy);
  check_result("backward", g, parameters_);
  return g;
}

void CheckedNetwork::per_sample_gradients(const NetworkCache& cache, const Matrix& gy,
                                          StridedMatrixRef out) const {
  inner_->per_sample_gradients(cache, gy, out);
}

Matrix CheckedNetwork::per_sample_gram(const NetworkCache& cache,
                                       const std::vector<Matrix>& cotangents) const {
  Matrix gram = inner_->per_sample_gram(cache, cotangents);
  const Index rows = cotangents.empty()
                         ? 0
                         : cotangents.front().cols() * static_cast<Index>(cotangents.size());
  check_result("per_sample_gram", gram, rows, rows);
  return gram;
}

Matrix CheckedNetwork::per_sample_gram_columns(const NetworkCache& cache,
                                               const std::vector<Matrix>& cotangents,
                                               const std::vector<Index>& selected) const {
  Matrix gram = inner_->per_sample_gram_columns(cache, cotangents, selected);
  const Index rows = cotangents.empty()
                         ? 0
                         : cotangents.front().cols() * static_cast<Index>(cotangents.size());
  check_result("per_sample_gram_columns", gram, rows, static_cast<Index>(selected.size()));
  return gram;
}

Matrix CheckedNetwork::jvp(const NetworkCache& cache, Index batch, const Vector& v) const {
  Matrix out = inner_->jvp(cache, batch, v);
  check_result("jvp", out, output_dim_, batch);
  return out;
}

std::vector<DenseLayerFactors> CheckedNetwork::dense_layer_factors(
    const NetworkCache& cache, const std::vector<Matrix>& cotangents) const {
  std::vector<DenseLayerFactors> layers = inner_->dense_layer_factors(cache, cotangents);
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const DenseLayerFactors& f = layers[l];
    const bool inside = f.offset >= 0 && f.outputs >= 1 && f.inputs >= 1 &&
                        f.offset + f.outputs * (f.inputs + 1) <= parameters_;
    if (!inside) {
      std::ostringstream msg;
      msg << "network '" << name() << "': dense_layer_factors layer " << l << " holds "
          << f.outputs << "×(" << f.inputs << " + 1) weights from entry " << f.offset
          << ", outside the " << parameters_ << " parameters";
      throw Error(msg.str());
    }
    check_result("dense_layer_factors (input_gram)", f.input_gram, f.inputs + 1, f.inputs + 1);
    check_result("dense_layer_factors (cotangent_gram)", f.cotangent_gram, f.outputs, f.outputs);
  }
  return layers;
}

}  // namespace physgrad
