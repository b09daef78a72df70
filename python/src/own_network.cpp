// The network of a script's own learning experiment: the dict of network options read key by key
// (each value checked and named), the network built from them, and the sizes the checks need.
#include "own_network.hpp"

#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/learn/learning_update.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/text.hpp"
#include "python_simulator.hpp"
#include "unet_case.hpp"

namespace physgrad::python {

namespace {

// Cells per channel of one sample at most (a 1024×1024 grid, or a line of 2^20 cells).
constexpr Index kMaxOwnNetworkCells = Index{1} << 20;
// Channels (filters) of a convolution at most, as the experiments' --filters.
constexpr long long kMaxOwnNetworkChannels = 256;

std::string shown_value(const py::handle& value) {
  return std::string(py::str(py::repr(value))).substr(0, 80);
}

// The dict `network`, read one key at a time: each value checked, named "network['KEY']".
class NetworkKeys {
 public:
  NetworkKeys(py::dict given, std::string who) : given_(std::move(given)), who_(std::move(who)) {}

  // Refuses a key that is not a string or not one of `known`.
  void allow(const std::vector<std::string>& known) const {
    for (const auto& [key, value] : given_) {
      if (!py::isinstance<py::str>(key)) {
        throw Error(who_ + ": network key " + shown_value(key) + " is not a string (" +
                    unknown_name_text("key", shown_value(key), known) + ")");
      }
      const std::string name = key.cast<std::string>();
      if (std::find(known.begin(), known.end(), name) == known.end()) {
        throw Error(who_ + ": network: " + unknown_name_text("key", name, known));
      }
    }
  }
  std::string where(const char* key) const { return who_ + ": network['" + key + "']"; }
  // The integer at `key` in [lowest, highest]; `fallback` when absent, or an Error naming the
  // key when it has none.
  long long integer(const char* key, std::optional<long long> fallback, long long lowest,
                    long long highest) const {
    if (given_.contains(key)) return to_integer(given_[key], where(key), lowest, highest);
    if (!fallback) throw Error(who_ + ": network needs '" + key + "' (an integer)");
    return *fallback;
  }
  bool flag(const char* key, bool fallback) const {
    if (!given_.contains(key)) return fallback;
    const py::object value = given_[key];
    if (!py::isinstance<py::bool_>(value)) {
      throw Error(where(key) + " is " + shown_value(value) + ", expected True or False");
    }
    return value.cast<bool>();
  }
  std::string choice(const char* key, const std::string& fallback,
                     const std::vector<std::string>& choices) const {
    if (!given_.contains(key)) return fallback;
    const py::object value = given_[key];
    const std::string text = py::isinstance<py::str>(value) ? value.cast<std::string>() : "";
    if (std::find(choices.begin(), choices.end(), text) == choices.end()) {
      throw Error(where(key) + " is " + shown_value(value) + ", expected one of " +
                  comma_list(choices));
    }
    return text;
  }
  // A list or tuple of integers in [lowest, highest], at least `count` of them; required.
  std::vector<Index> integers(const char* key, std::size_t count, long long lowest,
                              long long highest) const {
    if (!given_.contains(key)) throw Error(who_ + ": network needs '" + key + "' (a list)");
    const py::object value = given_[key];
    if (!py::isinstance<py::list>(value) && !py::isinstance<py::tuple>(value)) {
      throw Error(where(key) + " is " + shown_value(value) + ", expected a list of integers");
    }
    std::vector<Index> out;
    for (const py::handle item : value) {
      out.push_back(to_integer(item, where(key) + "[" + std::to_string(out.size()) + "]", lowest,
                               highest));
    }
    if (out.size() < count) {
      throw Error(where(key) + " is " + shown_value(value) + ", expected at least " +
                  std::to_string(count) + " entries");
    }
    return out;
  }

 private:
  py::dict given_;
  std::string who_;
};

std::vector<std::string> activation_names() {
  std::vector<std::string> names;
  for (const Activation a : {Activation::kRelu, Activation::kTanh, Activation::kSigmoid,
                             Activation::kSoftplus, Activation::kIdentity}) {
    names.push_back(to_string(a));
  }
  return names;
}

// dims and n, with n^dims at most kMaxOwnNetworkCells.
std::pair<int, Index> read_grid(const NetworkKeys& keys) {
  const int dims = static_cast<int>(keys.integer("dims", 2, 1, 2));
  const Index n = keys.integer("n", std::nullopt, 1, kMaxOwnNetworkCells);
  if (dims == 2 && n * n > kMaxOwnNetworkCells) {
    throw Error(keys.where("n") + " is " + std::to_string(n) + ": " + std::to_string(n) + "×" +
                std::to_string(n) + " = " + std::to_string(n * n) + " cells, more than " +
                std::to_string(kMaxOwnNetworkCells));
  }
  return {dims, n};
}

}  // namespace

OwnNetwork::OwnNetwork(const std::optional<std::vector<Index>>& widths,
                       const py::object& network, const std::string& who) {
  if (widths && !network.is_none()) {
    throw Error(who + ": give widths (an MLP) or network (a dict), not both");
  }
  if (widths) {
    widths_ = *widths;
    if (widths_.size() < 2) {
      throw Error(who + ": widths needs at least two layers, got " +
                  std::to_string(widths_.size()));
    }
    for (const Index w : widths_) {
      if (w < 1) throw Error(who + ": a width is " + std::to_string(w));
    }
  } else {
    if (network.is_none()) {
      throw Error(who + ": give widths (an MLP's layer widths) or network (a dict such as "
                        "{'kind': 'unet', 'n': 16})");
    }
    if (!py::isinstance<py::dict>(network)) {
      throw Error(who + ": network is " + shown_value(network) +
                  ", expected a dict such as {'kind': 'unet', 'n': 16}");
    }
    const auto given = py::reinterpret_borrow<py::dict>(network);
    if (!given.contains("kind")) throw Error(who + ": network needs 'kind' ('unet' or 'conv')");
    const std::string kind = NetworkKeys(given, who).choice("kind", "", {"unet", "conv"});
    if (kind == "unet") {
      read_unet(given, who);
    } else {
      read_stack(given, who);
    }
  }
  finish(who);
}

void OwnNetwork::read_unet(const py::dict& given, const std::string& who) {
  const NetworkKeys keys(given, who);
  keys.allow({"kind", "dims", "n", "in_channels", "out_channels", "levels", "filters",
              "activation", "batch_norm", "padding", "down", "up"});
  UNetOptions o;
  std::tie(o.dims, o.n) = read_grid(keys);
  o.levels = static_cast<int>(keys.integer("levels", 4, 1, 8));
  const Index factor = Index{1} << (o.levels - 1);
  if (o.n % factor != 0) {
    throw Error(keys.where("n") + " is " + std::to_string(o.n) + ", not a multiple of " +
                std::to_string(factor) + " (levels " + std::to_string(o.levels) +
                " halve the grid " + std::to_string(o.levels - 1) + " times)");
  }
  o.in_channels = keys.integer("in_channels", 1, 1, kMaxOwnNetworkChannels);
  o.out_channels = keys.integer("out_channels", 1, 1, kMaxOwnNetworkChannels);
  o.filters = keys.integer("filters", 16, 1, kMaxOwnNetworkChannels);
  o.activation = parse_activation(keys.choice("activation", "relu", activation_names()));
  o.batch_norm = keys.flag("batch_norm", false);
  o.padding = keys.choice("padding", "zero", {"zero", "periodic"}) == "periodic"
                  ? Padding::kPeriodic
                  : Padding::kZero;
  o.down = keys.choice("down", "maxpool", {"maxpool", "strided"}) == "strided"
               ? Downsample::kStrided
               : Downsample::kMaxPool;
  o.up = keys.choice("up", "bilinear", {"bilinear", "nearest"}) == "nearest" ? Upsample::kNearest
                                                                             : Upsample::kBilinear;
  unet_ = o;
}

void OwnNetwork::read_stack(const py::dict& given, const std::string& who) {
  const NetworkKeys keys(given, who);
  keys.allow({"kind", "dims", "n", "channels", "kernel", "activation", "padding"});
  Stack s;
  std::tie(s.dims, s.n) = read_grid(keys);
  s.channels = keys.integers("channels", 2, 1, kMaxOwnNetworkChannels);
  s.kernel = static_cast<int>(keys.integer("kernel", 3, 1, 15));
  if (s.kernel % 2 == 0) {
    throw Error(keys.where("kernel") + " is " + std::to_string(s.kernel) +
                ", expected an odd number (a centred kernel)");
  }
  s.activation = parse_activation(keys.choice("activation", "relu", activation_names()));
  s.padding = keys.choice("padding", "zero", {"zero", "periodic"}) == "periodic"
                  ? Padding::kPeriodic
                  : Padding::kZero;
  stack_ = s;
}

void OwnNetwork::finish(const std::string& who) {
  if (unet_ || stack_) {
    const Index n = unet_ ? unet_->n : stack_->n;
    require_memory(sample_bytes(0),
                   who + ": network n " + std::to_string(n) + " (one sample's activations)");
  }
  if (!widths_.empty()) {  // not built here: the run builds it
    input_dim_ = widths_.front();
    output_dim_ = widths_.back();
    return;
  }
  const std::unique_ptr<Network> network = build(0);
  input_dim_ = network->input_dim();
  output_dim_ = network->output_dim();
  parameters_ = static_cast<double>(network->num_parameters());
  options_ = network->describe();
  for (const char* derived : {"parameters", "input_dim", "output_dim"}) options_.erase(derived);
}

std::unique_ptr<Network> OwnNetwork::build(std::uint64_t seed) const {
  if (!widths_.empty()) {
    auto mlp = std::make_unique<Mlp>(widths_, Activation::kTanh);
    mlp->initialize(seed);
    return mlp;
  }
  auto network = std::make_unique<ConvNetwork>(
      unet_ ? ConvNetwork::unet(*unet_)
            : ConvNetwork::conv_stack(stack_->dims, stack_->n, stack_->channels, stack_->kernel,
                                      stack_->activation, stack_->padding));
  network->initialize(seed);
  return network;
}

std::string OwnNetwork::definition() const {
  if (widths_.empty()) return "network=" + options_.dump();
  std::string text = "widths=";
  for (std::size_t i = 0; i < widths_.size(); ++i) {
    if (i > 0) text += ',';
    text += std::to_string(widths_[i]);
  }
  return text;
}

double OwnNetwork::sample_bytes(Index data_values) const {
  if (!widths_.empty()) return run::sample_bytes(widths_, data_values);
  if (unet_) return experiments::unet_sample_bytes(*unet_, data_values);
  // Every convolution's output and its activation's, kept for the backward pass.
  const double cells = std::pow(static_cast<double>(stack_->n), stack_->dims);
  double values = static_cast<double>(data_values);
  for (const Index c : stack_->channels) values += 2.0 * static_cast<double>(c) * cells;
  return values * sizeof(double);
}

run::LearningExperiment::Shape OwnNetwork::shape(Index outputs) const {
  if (!widths_.empty()) return {outputs, widths_};
  return {outputs, {}, parameters_, parameters_};
}

void OwnNetwork::check_rules(const std::vector<std::string>& optimizers,
                             const std::string& prefix) const {
  if (!widths_.empty()) return;
  for (const std::string& id : optimizers) {
    std::unique_ptr<LearningUpdate> update;
    try {
      update = make_learning_update(id);
    } catch (const Error& e) {
      throw Error(prefix + e.what());
    }
    if (batch_norm() && update->need() == UpdateNeed::kStackedJacobian) {
      throw Error(prefix + "'" + id + "' needs per-sample Jacobians, which batch norm (the " +
                  "batch's own statistics) does not have; give the network batch_norm=False");
    }
  }
}

}  // namespace physgrad::python
