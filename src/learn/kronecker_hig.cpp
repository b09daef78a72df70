#include "physgrad/learn/kronecker_hig.hpp"

#include <lapacke.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "physgrad/error.hpp"
#include "physgrad/io/serialize.hpp"
#include "physgrad/spectral_cut.hpp"
#include "physgrad/timing.hpp"

namespace physgrad {

namespace {

// V f(Λ) Vᵀ for the symmetric positive semi-definite `m` = V Λ Vᵀ, the cut's weights on λ = σ²:
// f(λ) = (λ + damping·λ_max)^{−(1+κ)/2} for σ > rcond·σ_max, 0 otherwise (a zero matrix gives zero).
Matrix kronecker_factor_power(const Matrix& m, const SpectralCut& cut) {
  const Index n = m.rows();
  Matrix vectors = m;
  Vector lambda(n);
  if (n == 0) return vectors;
  const lapack_int info = LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'L', static_cast<lapack_int>(n),
                                         vectors.data(), static_cast<lapack_int>(n), lambda.data());
  if (info != 0) {
    throw NumericalError("kronecker factor: LAPACK dsyevd failed (info = " +
                         std::to_string(info) + ")");
  }
  const Vector weights = cut_squared(cut, lambda).weights;
  return vectors * weights.asDiagonal() * vectors.transpose();
}

// The layer's block of v as the outputs × (inputs + 1) matrix [W b].
Matrix kronecker_block(const KroneckerHigUpdate::Layer& layer, const Vector& v) {
  const Index in = layer.inputs, out = layer.outputs;
  if (!layer.transposed) return Eigen::Map<const Matrix>(v.data() + layer.offset, out, in + 1);
  Matrix block(out, in + 1);
  block.leftCols(in) = Eigen::Map<const Matrix>(v.data() + layer.offset, in, out).transpose();
  block.col(in) = v.segment(layer.offset + in * out, out);
  return block;
}

// Writes [W b] (outputs × (inputs + 1)) into the layer's entries of v.
void set_kronecker_block(const KroneckerHigUpdate::Layer& layer, const Matrix& block, Vector& v) {
  const Index in = layer.inputs, out = layer.outputs;
  if (!layer.transposed) {
    Eigen::Map<Matrix>(v.data() + layer.offset, out, in + 1) = block;
    return;
  }
  Eigen::Map<Matrix>(v.data() + layer.offset, in, out) = block.leftCols(in).transpose();
  v.segment(layer.offset + in * out, out) = block.col(in);
}

// K orthonormal columns in R^m drawn with `rng`: the Q of the QR of an m × K matrix of
// standard normals (its span uniform over the K-dimensional subspaces, E[Q Qᵀ] = (K/m)·I).
Matrix random_orthonormal_columns(Index m, Index k, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Matrix g(m, k);
  for (Index c = 0; c < k; ++c) {
    for (Index r = 0; r < m; ++r) g(r, c) = normal(rng);
  }
  const Eigen::HouseholderQR<Matrix> qr(g);
  return qr.householderQ() * Matrix::Identity(m, k);
}

// `samples`, listed in params() only when it is set (a run with all outputs keeps its config).
RuleOption<KroneckerHigOptions> sampled_directions_option() {
  RuleOption<KroneckerHigOptions> option =
      rule_option("samples", &KroneckerHigOptions::samples, integer_at_least(0),
                  "random output directions per sample at a refresh of the Kronecker factors, at "
                  "most the physics outputs m (0: all m, the exact factors)");
  option.applies = [](const KroneckerHigOptions& o) { return o.samples > 0; };
  return option;
}

// The seed of the generator of the output directions at reset().
constexpr std::uint64_t kDirectionSeed = 20261129;

std::string layer_key(std::size_t l, const char* what) {
  return "layer " + std::to_string(l) + " " + what;
}

}  // namespace

const OptionList<KroneckerHigOptions>& KroneckerHigOptions::descriptors() {
  static const OptionList<KroneckerHigOptions> options = {
      rule_option("lr", &KroneckerHigOptions::lr, positive(), "step size η"),
      kappa_option(&KroneckerHigOptions::cut),
      rcond_option(&KroneckerHigOptions::cut),
      damping_option(&KroneckerHigOptions::cut),
      in_group(OptionGroup::kInversion,
               rule_option("refresh", &KroneckerHigOptions::refresh, integer_at_least(1),
                           "steps from one refresh of the Kronecker factors to the next")),
      in_group(OptionGroup::kInversion,
               rule_option("factor_decay", &KroneckerHigOptions::factor_decay, fraction(),
                           "weight of the old Kronecker factors in their running average")),
      in_group(OptionGroup::kInversion, sampled_directions_option()),
  };
  return options;
}

KroneckerHigUpdate::KroneckerHigUpdate(Options options, const std::string& id)
    : options_(options),
      id_(listed_rule_id(rules(), id, rules()[options.cut.kappa == 1.0 ? 0 : 1].id)),
      rng_(kDirectionSeed) {
  check_options(id_, options_);
}

nlohmann::json KroneckerHigUpdate::params() const { return option_values(options_); }

void KroneckerHigUpdate::set_learning_rate(double lr) {
  Options changed = options_;
  changed.lr = lr;
  options_ = checked(id(), changed);
}

UpdateNeed KroneckerHigUpdate::need() const {
  if (steps_ % options_.refresh != 0) return UpdateNeed::kGradient;
  return options_.samples > 0 ? UpdateNeed::kWeightedFactors : UpdateNeed::kStackedJacobian;
}

void KroneckerHigUpdate::reset() {
  steps_ = 0;
  rng_.seed(kDirectionSeed);
  layers_.clear();
  input_powers_.clear();
  cotangent_powers_.clear();
}

void KroneckerHigUpdate::refresh_powers() {
  // Each factor takes the whole exponent (1+κ)/2 on its λ = σ².
  const SpectralCut& cut = options_.cut;
  std::vector<Matrix> inputs, cotangents;
  for (const Layer& layer : layers_) {
    inputs.push_back(kronecker_factor_power(layer.input_factor, cut));
    cotangents.push_back(kronecker_factor_power(layer.cotangent_factor, cut));
  }
  input_powers_ = std::move(inputs);
  cotangent_powers_ = std::move(cotangents);
}

Vector KroneckerHigUpdate::parameter_gradient(const BatchState& batch) const {
  if (batch.gradient.size() != 0) return batch.gradient;
  if (batch.jacobian == nullptr) throw Error(id() + ": the batch has neither ∇θ nor a Jacobian");
  return batch.jacobian->apply_transpose(batch.loss_gradient_y);
}

void KroneckerHigUpdate::average_factors(Layer& layer, const DenseLayerFactors& f, double weight,
                                         double batch_size, std::size_t l) const {
  if (weight > 0 && (layer.offset != f.offset || layer.outputs != f.outputs ||
                     layer.inputs != f.inputs || layer.transposed != f.transposed)) {
    throw Error(id() + ": dense layer " + std::to_string(l) +
                " does not have the shape of its saved factors");
  }
  layer.offset = f.offset;
  layer.outputs = f.outputs;
  layer.inputs = f.inputs;
  layer.transposed = f.transposed;
  const Matrix a = f.input_gram / batch_size;
  if (weight > 0) {
    layer.input_factor = weight * layer.input_factor + (1 - weight) * a;
    layer.cotangent_factor = weight * layer.cotangent_factor + (1 - weight) * f.cotangent_gram;
  } else {
    layer.input_factor = a;
    layer.cotangent_factor = f.cotangent_gram;
  }
  if (!all_finite(layer.input_factor) || !all_finite(layer.cotangent_factor)) {
    throw NumericalError(id() + ": non-finite Kronecker factor of dense layer " +
                         std::to_string(l));
  }
}

std::vector<DenseLayerFactors> KroneckerHigUpdate::sampled_factors(const BatchState& batch,
                                                                   std::mt19937_64& rng) const {
  if (!batch.weighted_factors) {
    throw Error(id() + ": this step refreshes the Kronecker factors from sampled directions and "
                "needs the batch's weighted factors");
  }
  const Index m = batch.outputs, k = options_.samples, b = batch.batch_size;
  if (k > m) {
    throw Error(id() + ": samples " + std::to_string(k) + " exceeds the " + std::to_string(m) +
                " physics outputs per sample");
  }
  const double scale = std::sqrt(static_cast<double>(m) / static_cast<double>(k));
  std::vector<Matrix> weights(static_cast<std::size_t>(k), Matrix(m, b));
  for (Index i = 0; i < b; ++i) {
    const Matrix q = random_orthonormal_columns(m, k, rng);
    for (Index j = 0; j < k; ++j) weights[static_cast<std::size_t>(j)].col(i) = scale * q.col(j);
  }
  return batch.weighted_factors(weights);
}

std::vector<KroneckerHigUpdate::Layer> KroneckerHigUpdate::refreshed_layers(
    const std::vector<DenseLayerFactors>& factors, double batch_size) const {
  std::vector<Layer> layers = layers_;
  const double weight = layers.empty() ? 0.0 : options_.factor_decay;
  if (!layers.empty() && layers.size() != factors.size()) {
    throw Error(id() + ": the network has " + std::to_string(factors.size()) +
                " dense layers, the saved factors " + std::to_string(layers.size()));
  }
  layers.resize(factors.size());
  for (std::size_t l = 0; l < factors.size(); ++l) {
    average_factors(layers[l], factors[l], weight, batch_size, l);
  }
  return layers;
}

void KroneckerHigUpdate::check_covers(const std::vector<Layer>& layers, Index parameters) const {
  Index covered = 0;
  for (const Layer& layer : layers) covered += layer.outputs * (layer.inputs + 1);
  if (covered != parameters) {
    throw Error(id() + ": the dense layers hold " + std::to_string(covered) + " of the " +
                std::to_string(parameters) + " parameters");
  }
}

void KroneckerHigUpdate::install(std::vector<Layer>& refreshed, bool refreshing) {
  if (refreshing) std::swap(refreshed, layers_);
  if (!refreshing && input_powers_.size() == layers_.size()) return;
  try {
    refresh_powers();
  } catch (...) {
    if (refreshing) std::swap(refreshed, layers_);
    throw;
  }
}

Vector KroneckerHigUpdate::preconditioned_step(const Vector& gradient) const {
  Vector delta = Vector::Zero(gradient.size());
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    const Layer& layer = layers_[l];
    const Matrix g = kronecker_block(layer, gradient);
    set_kronecker_block(layer, -options_.lr * (cotangent_powers_[l] * g * input_powers_[l]),
                        delta);
  }
  return delta;
}

Step KroneckerHigUpdate::step(const BatchState& batch) {
  const bool refreshing = need() != UpdateNeed::kGradient;
  const bool sampled = refreshing && options_.samples > 0;
  if (refreshing && !sampled && batch.jacobian == nullptr) {
    throw Error(id() + ": this step refreshes the Kronecker factors and needs the stacked Jacobian");
  }
  const Vector gradient = parameter_gradient(batch);
  Step step;
  // The refreshed factors and the generator in locals first: nothing changes when something
  // below throws.
  std::vector<Layer> layers;
  std::mt19937_64 rng = rng_;
  if (refreshing) {
    const auto start = std::chrono::steady_clock::now();
    layers = sampled ? refreshed_layers(sampled_factors(batch, rng),
                                        static_cast<double>(batch.batch_size))
                     : refreshed_layers(batch.jacobian->dense_layer_factors(),
                                        static_cast<double>(batch.jacobian->batch()));
    step.jacobian_seconds = seconds_since(start);
  }
  check_covers(refreshing ? layers : layers_, gradient.size());
  const auto start = std::chrono::steady_clock::now();
  install(layers, refreshing);
  rng_ = rng;
  step.delta = preconditioned_step(gradient);
  ++steps_;
  step.inversion_seconds = seconds_since(start);
  return step;
}

nlohmann::json KroneckerHigUpdate::state() const {
  if (steps_ == 0) return nullptr;
  nlohmann::json layers = nlohmann::json::array();
  for (const Layer& layer : layers_) {
    layers.push_back({{"offset", layer.offset},
                      {"outputs", layer.outputs},
                      {"inputs", layer.inputs},
                      {"transposed", layer.transposed},
                      {"input_factor", vector_to_json(layer.input_factor.reshaped())},
                      {"cotangent_factor", vector_to_json(layer.cotangent_factor.reshaped())}});
  }
  nlohmann::json state = {{"steps", steps_}, {"layers", layers}};
  if (options_.samples > 0) {
    std::ostringstream text;
    text << rng_;
    state["directions_rng"] = text.str();
  }
  return state;
}

void KroneckerHigUpdate::restore(const nlohmann::json& state, Index parameter_count) {
  reset();
  if (state.is_null()) return;
  const long long steps = integer_from_json(state, "steps", 1);
  if (!state.contains("layers") || !state.at("layers").is_array()) {
    throw Error("checkpoint field 'layers': expected an array");
  }
  std::vector<Layer> layers;
  Index covered = 0;
  for (const nlohmann::json& entry : state.at("layers")) {
    const std::size_t l = layers.size();
    Layer layer;
    layer.offset = static_cast<Index>(integer_from_json(entry, "offset"));
    layer.outputs = static_cast<Index>(integer_from_json(entry, "outputs", 1));
    layer.inputs = static_cast<Index>(integer_from_json(entry, "inputs", 1));
    if (entry.contains("transposed")) {  // absent in checkpoints of dense networks
      if (!entry.at("transposed").is_boolean()) {
        throw Error("checkpoint field '" + layer_key(l, "transposed") +
                    "': expected true or false");
      }
      layer.transposed = entry.at("transposed").get<bool>();
    }
    covered += layer.outputs * (layer.inputs + 1);
    if (layer.offset + layer.outputs * (layer.inputs + 1) > parameter_count) {
      throw Error("checkpoint field '" + layer_key(l, "offset") + "': the layer ends beyond the " +
                  std::to_string(parameter_count) + " parameters");
    }
    const Index a = layer.inputs + 1, s = layer.outputs;
    layer.input_factor = vector_from_json(entry, "input_factor", a * a).reshaped(a, a);
    layer.cotangent_factor = vector_from_json(entry, "cotangent_factor", s * s).reshaped(s, s);
    layers.push_back(std::move(layer));
  }
  if (covered != parameter_count) {
    throw Error("checkpoint field 'layers': they hold " + std::to_string(covered) + " of the " +
                std::to_string(parameter_count) + " parameters");
  }
  std::mt19937_64 rng = rng_;
  if (state.contains("directions_rng")) {  // absent without samples
    std::istringstream text(state.at("directions_rng").is_string()
                                ? state.at("directions_rng").get<std::string>()
                                : std::string());
    text >> rng;
    if (text.fail()) {
      throw Error("checkpoint field 'directions_rng': expected the state of the direction "
                  "generator");
    }
  }
  steps_ = steps;
  layers_ = std::move(layers);
  rng_ = rng;
}

}  // namespace physgrad
