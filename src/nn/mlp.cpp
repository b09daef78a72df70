#include "physgrad/nn/mlp.hpp"

#include <cblas.h>

#include <array>
#include <cmath>
#include <random>
#include <sstream>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/nn/dense_layer_gram.hpp"
#include "physgrad/text.hpp"

namespace physgrad {

namespace {

constexpr NameTable<Init, 2> kInitNames{{
    {Init::kGlorotUniform, "glorot"},
    {Init::kHeUniform, "he"},
}};

std::string shape_text(Index rows, Index cols) {
  return std::to_string(rows) + "x" + std::to_string(cols);
}

void check_layer(const Mlp& mlp, Index layer) {
  if (layer < 0 || layer >= mlp.num_layers()) {
    throw Error(std::string("Mlp: layer ") + std::to_string(layer) + " out of range [0, " +
                std::to_string(mlp.num_layers()) + ")");
  }
}

// parameters() hands out θ by reference; make sure nobody resized it.
void check_parameters(const Mlp& mlp) {
  if (mlp.parameters().size() != mlp.num_parameters()) {
    throw Error(std::string("Mlp: parameters() was resized to ") +
                std::to_string(mlp.parameters().size()) + ", the network has " +
                std::to_string(mlp.num_parameters()));
  }
}

void check_input(const Mlp& mlp, const Matrix& x) {
  check_parameters(mlp);
  if (x.rows() != mlp.input_dim()) {
    throw Error(std::string("Mlp::forward: input x is ") + shape_text(x.rows(), x.cols()) +
                ", expected " + std::to_string(mlp.input_dim()) + " rows");
  }
}

const MlpCache& mlp_cache(const NetworkCache& cache) {
  const auto* own = dynamic_cast<const MlpCache*>(&cache);
  if (own == nullptr) throw Error("Mlp: the cache comes from another kind of network");
  return *own;
}

// Checks that `cache` comes from forward() on this network; returns B.
Index check_cache(const Mlp& mlp, const MlpCache& cache) {
  check_parameters(mlp);
  const auto& widths = mlp.widths();
  if (cache.activations.size() != widths.size() ||
      cache.derivatives.size() + 1 != widths.size()) {
    throw Error(std::string("Mlp: cache holds ") + std::to_string(cache.activations.size()) +
                " activations and " + std::to_string(cache.derivatives.size()) +
                " derivatives; run forward(x, cache) on this network first");
  }
  const Index batch = cache.activations[0].cols();
  const auto expect = [&](const Matrix& m, Index rows, const std::string& what) {
    if (m.rows() != rows || m.cols() != batch) {
      throw Error(std::string("Mlp: ") + what + " is " + shape_text(m.rows(), m.cols()) +
                  ", expected " + shape_text(rows, batch));
    }
  };
  for (std::size_t l = 0; l < widths.size(); ++l) {
    expect(cache.activations[l], widths[l],
           std::string("cache.activations[") + std::to_string(l) + "]");
    if (l > 0) {
      expect(cache.derivatives[l - 1], widths[l],
             std::string("cache.derivatives[") + std::to_string(l - 1) + "]");
    }
  }
  return batch;
}

// The same, and that gy (output_dim × B) matches it; returns B.
Index check_cache(const Mlp& mlp, const MlpCache& cache, const Matrix& gy) {
  const Index batch = check_cache(mlp, cache);
  if (gy.rows() != mlp.output_dim() || gy.cols() != batch) {
    throw Error(std::string("Mlp: output cotangent gy is ") + shape_text(gy.rows(), gy.cols()) +
                ", expected " + shape_text(mlp.output_dim(), batch));
  }
  return batch;
}

// Runs the backward sweep of the batch in `cache` with output cotangents gy, calling
// visit(l, δ_l) for l = L−1 … 0, where δ_l = ∂(Σ_b gy_bᵀ f(x_b))/∂z_l (width[l+1] × B).
template <typename Visit>
void backpropagate(const Mlp& mlp, const MlpCache& cache, const Matrix& gy, Visit&& visit) {
  Matrix delta = gy.cwiseProduct(cache.derivatives.back());
  for (Index l = mlp.num_layers() - 1;; --l) {
    visit(l, delta);
    if (l == 0) return;
    delta = (mlp.weight(l).transpose() * delta).cwiseProduct(cache.derivatives[l - 1]);
  }
}

}  // namespace

std::string to_string(Init init) {
  return name_of(kInitNames, init, "Init");
}

Init parse_init(const std::string& text) { return value_named(kInitNames, text, "init"); }

Mlp::Mlp(std::vector<Index> widths, Activation hidden, Activation output)
    : widths_(std::move(widths)), hidden_(hidden), output_(output) {
  if (widths_.size() < 2) {
    throw Error(std::string("Mlp: widths need at least 2 entries {input, ..., output}, got ") +
                std::to_string(widths_.size()));
  }
  offsets_.push_back(0);
  for (std::size_t i = 0; i < widths_.size(); ++i) {
    if (widths_[i] < 1) {
      std::ostringstream msg;
      msg << "Mlp: widths[" << i << "] = " << widths_[i] << ", every width must be >= 1";
      throw Error(msg.str());
    }
    if (i > 0) offsets_.push_back(offsets_.back() + (widths_[i - 1] + 1) * widths_[i]);
  }
  theta_ = Vector::Zero(offsets_.back());
}

nlohmann::json Mlp::describe() const {
  return {{"kind", "mlp"},
          {"widths", widths_},
          {"hidden", to_string(hidden_)},
          {"output", to_string(output_)}};
}

Activation Mlp::activation(Index layer) const {
  return layer + 1 == num_layers() ? output_ : hidden_;
}

Eigen::Map<const Matrix> Mlp::weight(Index layer) const {
  check_layer(*this, layer);
  return {theta_.data() + offsets_[layer], widths_[layer + 1], widths_[layer]};
}

Eigen::Map<Matrix> Mlp::weight(Index layer) {
  check_layer(*this, layer);
  return {theta_.data() + offsets_[layer], widths_[layer + 1], widths_[layer]};
}

Eigen::Map<const Vector> Mlp::bias(Index layer) const {
  check_layer(*this, layer);
  return {theta_.data() + offsets_[layer + 1] - widths_[layer + 1], widths_[layer + 1]};
}

Eigen::Map<Vector> Mlp::bias(Index layer) {
  check_layer(*this, layer);
  return {theta_.data() + offsets_[layer + 1] - widths_[layer + 1], widths_[layer + 1]};
}

void Mlp::initialize(std::uint64_t seed, Init init) {
  std::mt19937_64 engine(seed);
  for (Index l = 0; l < num_layers(); ++l) {
    const auto fan_in = static_cast<double>(widths_[l]);
    const auto fan_out = static_cast<double>(widths_[l + 1]);
    const double limit =
        std::sqrt(6.0 / (init == Init::kGlorotUniform ? fan_in + fan_out : fan_in));
    for (double& w : theta_.segment(offsets_[l], widths_[l] * widths_[l + 1])) {
      const double u = static_cast<double>(engine() >> 11) * 0x1p-53;  // uniform in [0, 1)
      w = limit * (2 * u - 1);
    }
    bias(l).setZero();
  }
}

Matrix Mlp::forward(const Matrix& x) const {
  check_input(*this, x);
  Matrix a = x;
  for (Index l = 0; l < num_layers(); ++l) {
    Matrix z = (weight(l) * a).colwise() + bias(l);
    apply(activation(l), z.array(), z.array());
    a = std::move(z);
  }
  return a;
}

std::unique_ptr<NetworkCache> Mlp::new_cache() const { return std::make_unique<MlpCache>(); }

Matrix Mlp::forward(const Matrix& x, NetworkCache& network_cache) const {
  auto* own = dynamic_cast<MlpCache*>(&network_cache);
  if (own == nullptr) throw Error("Mlp::forward: the cache comes from another kind of network");
  MlpCache& cache = *own;
  check_input(*this, x);
  cache.activations.resize(widths_.size());
  cache.derivatives.resize(widths_.size() - 1);
  cache.activations[0] = x;
  for (Index l = 0; l < num_layers(); ++l) {
    Matrix& a = cache.activations[l + 1];
    Matrix& d = cache.derivatives[l];
    a.noalias() = weight(l) * cache.activations[l];
    a.colwise() += bias(l);
    d.resize(a.rows(), a.cols());
    apply_with_derivative(activation(l), a.array(), d.array());
  }
  return cache.activations.back();
}

Vector Mlp::backward(const NetworkCache& cache, const Matrix& gy) const {
  return backward(cache, gy, nullptr);
}

Vector Mlp::backward(const NetworkCache& network_cache, const Matrix& gy, Matrix* gx) const {
  const MlpCache& cache = mlp_cache(network_cache);
  check_cache(*this, cache, gy);
  Vector grad(num_parameters());
  backpropagate(*this, cache, gy, [&](Index l, const Matrix& delta) {
    const Index rows = widths_[l + 1];
    const Index cols = widths_[l];
    Eigen::Map<Matrix>(grad.data() + offsets_[l], rows, cols).noalias() =
        delta * cache.activations[l].transpose();
    grad.segment(offsets_[l] + rows * cols, rows) = delta.rowwise().sum();
    if (l == 0 && gx != nullptr) *gx = weight(0).transpose() * delta;
  });
  return grad;
}

void Mlp::per_sample_gradients(const NetworkCache& network_cache, const Matrix& gy,
                               StridedMatrixRef out) const {
  const MlpCache& cache = mlp_cache(network_cache);
  const Index batch = check_cache(*this, cache, gy);
  if (out.rows() != batch || out.cols() != num_parameters()) {
    throw Error(std::string("Mlp::per_sample_gradients: output block is ") +
                shape_text(out.rows(), out.cols()) + ", expected " +
                shape_text(batch, num_parameters()));
  }
  backpropagate(*this, cache, gy, [&](Index l, const Matrix& delta) {
    // Sample-major copies: column j of delta_t is δ_l[j, :]ᵀ, column i of input_t a_{l−1}[i, :]ᵀ.
    const Matrix delta_t = delta.transpose();
    const Matrix input_t = cache.activations[l].transpose();
    const Index rows = widths_[l + 1];
    for (Index i = 0; i < widths_[l]; ++i) {  // ∂/∂W_l[:, i], all samples: δ_l ∘ a_{l−1}[i, :]
      out.middleCols(offsets_[l] + i * rows, rows) =
          delta_t.array().colwise() * input_t.col(i).array();
    }
    out.middleCols(offsets_[l] + widths_[l] * rows, rows) = delta_t;
  });
}

void Mlp::sweep_cotangents(
    const NetworkCache& network_cache, const std::vector<Matrix>& cotangents,
    const std::function<void(Index layer, const Matrix& deltas, const Matrix& inputs)>& visit)
    const {
  const MlpCache& cache = mlp_cache(network_cache);
  for (const Matrix& block : cotangents) check_cache(*this, cache, block);
  const Index batch = cache.activations[0].cols();
  const auto blocks = static_cast<Index>(cotangents.size());
  // δ_l of all K·B cotangents in one sweep (column k·B + i for block k, sample i); each layer's
  // σ' applies to column k·B + i as to sample i.
  const auto times_slope = [&](Matrix& delta, const Matrix& slope) {
    for (Index k = 0; k < blocks; ++k) delta.middleCols(k * batch, batch).array() *= slope.array();
  };
  Matrix delta(output_dim(), blocks * batch);
  for (Index k = 0; k < blocks; ++k) {
    delta.middleCols(k * batch, batch) = cotangents[static_cast<std::size_t>(k)];
  }
  times_slope(delta, cache.derivatives.back());
  Matrix next;
  for (Index l = num_layers() - 1;; --l) {
    visit(l, delta, cache.activations[static_cast<std::size_t>(l)]);
    if (l == 0) break;
    next.noalias() = weight(l).transpose() * delta;
    times_slope(next, cache.derivatives[static_cast<std::size_t>(l - 1)]);
    delta.swap(next);
  }
}

namespace {

// M Mᵀ (symmetric) by BLAS dsyrk on the lower triangle, mirrored.
Matrix mlp_outer_gram(const Matrix& m) {
  Matrix out = Matrix::Zero(m.rows(), m.rows());
  if (m.size() == 0) return out;
  cblas_dsyrk(CblasColMajor, CblasLower, CblasNoTrans, static_cast<blasint>(m.rows()),
              static_cast<blasint>(m.cols()), 1.0, m.data(), static_cast<blasint>(m.rows()), 0.0,
              out.data(), static_cast<blasint>(m.rows()));
  out.triangularView<Eigen::StrictlyUpper>() = out.transpose();
  return out;
}

// K·B columns of the Gram matrix of K cotangent blocks over `batch` samples.
Index gram_columns(const std::vector<Matrix>& cotangents, Index batch) {
  return static_cast<Index>(cotangents.size()) * batch;
}

}  // namespace

Matrix Mlp::per_sample_gram(const NetworkCache& network_cache,
                            const std::vector<Matrix>& cotangents) const {
  const Index batch = mlp_cache(network_cache).activations[0].cols();
  DenseLayerGram gram(gram_columns(cotangents, batch), batch);
  sweep_cotangents(network_cache, cotangents,
                   [&gram](Index, const Matrix& deltas, const Matrix& inputs) {
                     gram.add(deltas, inputs);
                   });
  return gram.finish();
}

Matrix Mlp::per_sample_gram_columns(const NetworkCache& network_cache,
                                    const std::vector<Matrix>& cotangents,
                                    const std::vector<Index>& selected) const {
  const Index batch = mlp_cache(network_cache).activations[0].cols();
  DenseLayerGram gram(gram_columns(cotangents, batch), batch, selected);
  sweep_cotangents(network_cache, cotangents,
                   [&gram](Index, const Matrix& deltas, const Matrix& inputs) {
                     gram.add(deltas, inputs);
                   });
  return gram.finish();
}

Matrix Mlp::jvp(const NetworkCache& network_cache, Index batch, const Vector& v) const {
  const MlpCache& cache = mlp_cache(network_cache);
  if (check_cache(*this, cache) != batch || v.size() != num_parameters()) {
    throw Error("Mlp::jvp: a direction of " + std::to_string(v.size()) + " entries on " +
                std::to_string(batch) + " samples, expected " +
                std::to_string(num_parameters()) + " on the " +
                std::to_string(cache.activations[0].cols()) + " cached");
  }
  Matrix tangent;  // ȧ_{l−1}; none for the input
  for (Index l = 0; l < num_layers(); ++l) {
    const Eigen::Map<const Matrix> dw(v.data() + offsets_[l], widths_[l + 1], widths_[l]);
    const Eigen::Map<const Vector> db(v.data() + offsets_[l] + widths_[l + 1] * widths_[l],
                                      widths_[l + 1]);
    Matrix dz = dw * cache.activations[static_cast<std::size_t>(l)];
    if (l > 0) dz.noalias() += weight(l) * tangent;
    dz.colwise() += db;
    tangent = dz.cwiseProduct(cache.derivatives[static_cast<std::size_t>(l)]);
  }
  return tangent;
}

std::vector<DenseLayerFactors> Mlp::dense_layer_factors(
    const NetworkCache& network_cache, const std::vector<Matrix>& cotangents) const {
  std::vector<DenseLayerFactors> layers(static_cast<std::size_t>(num_layers()));
  sweep_cotangents(network_cache, cotangents,
                   [&](Index l, const Matrix& deltas, const Matrix& inputs) {
                     DenseLayerFactors& f = layers[static_cast<std::size_t>(l)];
                     f.offset = offsets_[l];
                     f.outputs = widths_[l + 1];
                     f.inputs = widths_[l];
                     Matrix extended(f.inputs + 1, inputs.cols());  // ā = [a; 1]
                     extended.topRows(f.inputs) = inputs;
                     extended.row(f.inputs).setOnes();
                     f.input_gram = mlp_outer_gram(extended);
                     f.cotangent_gram = mlp_outer_gram(deltas);
                   });
  return layers;
}

}  // namespace physgrad
