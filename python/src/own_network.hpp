// The network of a script's own learning experiment (physgrad.LearningExperiment): a tanh MLP of
// `widths`, or a ConvNetwork — phiml's U-net or a plain stack — read key by key from a dict.
#pragma once

#include <pybind11/pybind11.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "physgrad/nn/conv_net.hpp"
#include "physgrad/run/cases/learning_experiment.hpp"

namespace physgrad::python {

class OwnNetwork {
 public:
  // Exactly one of `widths` (an MLP's layer widths) and `network` (None, or a dict
  // {"kind": "unet" | "conv", …}, docs/python.md). Throws Error, `who` first, naming a missing,
  // unknown or misspelt key, or the key and value of one that is of the wrong type or out of
  // range, or when one sample's activations would not fit in memory.
  OwnNetwork(const std::optional<std::vector<Index>>& widths, const pybind11::object& network,
             const std::string& who);

  Index input_dim() const { return input_dim_; }
  Index output_dim() const { return output_dim_; }
  bool batch_norm() const { return unet_ && unet_->batch_norm; }
  // The network a run starts from, initialized from `seed`.
  std::unique_ptr<Network> build(std::uint64_t seed) const;
  // For the experiment's definition: "widths=2,8,2" or "network={…}" (every option, defaults
  // filled in, as JSON).
  std::string definition() const;
  // Bytes one sample needs at least: its `data_values` doubles and the activations kept for the
  // backward pass.
  double sample_bytes(Index data_values) const;
  // What LearningExperiment's size checks need, for `outputs` physics outputs per sample.
  run::LearningExperiment::Shape shape(Index outputs) const;
  // Throws Error, `prefix` first, naming the first of `optimizers` a ConvNetwork cannot be
  // trained by: a Kronecker-factored rule (it needs dense layers), or, with batch norm (whose
  // batch statistics tie the samples together), one that needs per-sample Jacobians.
  void check_rules(const std::vector<std::string>& optimizers, const std::string& prefix) const;

 private:
  struct Stack {
    int dims = 2;
    Index n = 0;
    std::vector<Index> channels;
    int kernel = 3;
    Activation activation = Activation::kRelu;
    Padding padding = Padding::kZero;
  };
  void read_unet(const pybind11::dict& given, const std::string& who);
  void read_stack(const pybind11::dict& given, const std::string& who);
  // The input and output sizes, |θ| and the options of the built network; checks the memory.
  void finish(const std::string& who);

  std::vector<Index> widths_;  // an MLP's; empty for a ConvNetwork
  std::optional<UNetOptions> unet_;
  std::optional<Stack> stack_;
  nlohmann::json options_;  // a ConvNetwork's options, every one
  Index input_dim_ = 0, output_dim_ = 0;
  double parameters_ = 0;
};

}  // namespace physgrad::python
