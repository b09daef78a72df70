// The builders of ConvNetwork: the tape of a plain stack or a U-net, θ's layout, initialisation.
#include <cmath>
#include <functional>
#include <random>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/nn/conv_net.hpp"

namespace physgrad {

namespace {

void check_unet_options(const UNetOptions& o) {
  const std::string where = "ConvNetwork::unet: ";
  if (o.dims != 1 && o.dims != 2) {
    throw Error(where + "dims " + std::to_string(o.dims) + " is not 1 or 2");
  }
  if (o.levels < 1) throw Error(where + "levels " + std::to_string(o.levels) + " is below 1");
  if (o.levels > 30) throw Error(where + "levels " + std::to_string(o.levels) + " is above 30");
  const Index factor = Index{1} << (o.levels - 1);
  if (o.n < 1 || o.n % factor != 0) {
    throw Error(where + "n " + std::to_string(o.n) +
                " is not a positive multiple of 2^(levels-1) = " + std::to_string(factor));
  }
  if (o.in_channels < 1 || o.out_channels < 1 || o.filters < 1) {
    throw Error(where + "in_channels " + std::to_string(o.in_channels) + ", out_channels " +
                std::to_string(o.out_channels) + " and filters " + std::to_string(o.filters) +
                " must all be at least 1");
  }
}

// conv → [batch norm] → activation, twice; the first conv has stride `stride`.
int double_conv(const UNetOptions& o, int slot, int stride,
                const std::function<int(int, Index, int, int)>& conv,
                const std::function<int(int)>& norm, const std::function<int(int)>& act) {
  for (int k = 0; k < 2; ++k) {
    slot = conv(slot, o.filters, 3, k == 0 ? stride : 1);
    if (o.batch_norm) slot = norm(slot);
    slot = act(slot);
  }
  return slot;
}

}  // namespace

ConvNetwork::ConvNetwork(std::string name, Grid grid, Index channels) : name_(std::move(name)) {
  slot_channels_.push_back(channels);
  slot_grids_.push_back(grid);
}

Index ConvNetwork::slot_rows(int slot) const {
  const auto s = static_cast<std::size_t>(slot);
  return slot_channels_[s] * slot_grids_[s].cells();
}

int ConvNetwork::add_conv(int input, Index channels_out, int kernel, int stride, Padding padding) {
  ConvOp op;
  op.kind = ConvOpKind::kConv;
  op.input = input;
  op.channels_in = slot_channels_[static_cast<std::size_t>(input)];
  op.channels_out = channels_out;
  op.grid_in = slot_grids_[static_cast<std::size_t>(input)];
  op.kernel = kernel;
  op.stride = stride;
  op.geometry = std::make_shared<ConvGeometry>(op.grid_in, kernel, stride, padding);
  op.grid_out = op.geometry->out();
  op.offset = num_parameters_;
  num_parameters_ += (op.channels_in * op.geometry->taps() + 1) * channels_out;
  ops_.push_back(op);
  slot_channels_.push_back(channels_out);
  slot_grids_.push_back(op.grid_out);
  return static_cast<int>(ops_.size());
}

int ConvNetwork::add_activation(int input, Activation activation) {
  ConvOp op;
  op.kind = ConvOpKind::kActivation;
  op.input = input;
  op.channels_in = op.channels_out = slot_channels_[static_cast<std::size_t>(input)];
  op.grid_in = op.grid_out = slot_grids_[static_cast<std::size_t>(input)];
  op.activation = activation;
  ops_.push_back(op);
  slot_channels_.push_back(op.channels_out);
  slot_grids_.push_back(op.grid_out);
  return static_cast<int>(ops_.size());
}

int ConvNetwork::add_batch_norm(int input) {
  const int slot = add_activation(input, Activation::kIdentity);
  ConvOp& op = ops_.back();
  op.kind = ConvOpKind::kBatchNorm;
  op.offset = num_parameters_;
  num_parameters_ += 2 * op.channels_out;
  return slot;
}

int ConvNetwork::add_max_pool(int input) {
  const int slot = add_activation(input, Activation::kIdentity);
  ConvOp& op = ops_.back();
  op.kind = ConvOpKind::kMaxPool;
  op.stencil = std::make_shared<GridStencil>(GridStencil::pool_windows(op.grid_in));
  op.grid_out = op.stencil->out();
  slot_grids_.back() = op.grid_out;
  return slot;
}

int ConvNetwork::add_upsample(int input, Upsample mode, Padding padding) {
  const int slot = add_activation(input, Activation::kIdentity);
  ConvOp& op = ops_.back();
  op.kind = ConvOpKind::kUpsample;
  op.stencil = std::make_shared<GridStencil>(GridStencil::upsample(op.grid_in, mode, padding));
  op.grid_out = op.stencil->out();
  slot_grids_.back() = op.grid_out;
  return slot;
}

int ConvNetwork::add_concat(int skip, int input) {
  const int slot = add_activation(input, Activation::kIdentity);
  ConvOp& op = ops_.back();
  op.kind = ConvOpKind::kConcat;
  op.skip = skip;
  op.channels_out = op.channels_in + slot_channels_[static_cast<std::size_t>(skip)];
  slot_channels_.back() = op.channels_out;
  return slot;
}

void ConvNetwork::finish(nlohmann::json options) {
  input_dim_ = slot_rows(0);
  output_dim_ = slot_rows(static_cast<int>(ops_.size()));
  options_ = std::move(options);
  theta_ = Vector::Zero(num_parameters_);
}

ConvNetwork ConvNetwork::unet(const UNetOptions& o) {
  check_unet_options(o);
  ConvNetwork net("ConvNetwork(unet)", Grid{o.dims, o.n}, o.in_channels);
  const auto conv = [&](int s, Index c, int k, int stride) {
    return net.add_conv(s, c, k, stride, o.padding);
  };
  const auto norm = [&](int s) { return net.add_batch_norm(s); };
  const auto act = [&](int s) { return net.add_activation(s, o.activation); };
  std::vector<int> skips{double_conv(o, 0, 1, conv, norm, act)};
  for (int level = 1; level < o.levels; ++level) {
    int slot = skips.back();
    if (o.down == Downsample::kMaxPool) slot = net.add_max_pool(slot);
    skips.push_back(double_conv(o, slot, o.down == Downsample::kStrided ? 2 : 1, conv, norm, act));
  }
  int slot = skips.back();
  for (int level = o.levels - 2; level >= 0; --level) {
    slot = net.add_upsample(slot, o.up, o.padding);
    slot = net.add_concat(skips[static_cast<std::size_t>(level)], slot);
    slot = double_conv(o, slot, 1, conv, norm, act);
  }
  net.add_conv(slot, o.out_channels, 1, 1, o.padding);
  net.finish({{"kind", "unet"},
              {"dims", o.dims},
              {"n", o.n},
              {"in_channels", o.in_channels},
              {"out_channels", o.out_channels},
              {"levels", o.levels},
              {"filters", o.filters},
              {"activation", to_string(o.activation)},
              {"batch_norm", o.batch_norm},
              {"padding", to_string(o.padding)},
              {"down", to_string(o.down)},
              {"up", to_string(o.up)}});
  return net;
}

ConvNetwork ConvNetwork::conv_stack(int dims, Index n, const std::vector<Index>& channels,
                                    int kernel, Activation activation, Padding padding) {
  const std::string where = "ConvNetwork::conv_stack: ";
  if (dims != 1 && dims != 2)
    throw Error(where + "dims " + std::to_string(dims) + " is not 1 or 2");
  if (n < 1) throw Error(where + "n " + std::to_string(n) + " is below 1");
  if (kernel < 1 || kernel % 2 == 0) {
    throw Error(where + "kernel " + std::to_string(kernel) + " is not a positive odd number");
  }
  if (channels.size() < 2) {
    throw Error(where + "channels has " + std::to_string(channels.size()) +
                " entries, needs at least 2 (in, out)");
  }
  for (const Index c : channels) {
    if (c < 1) throw Error(where + "a channel count is " + std::to_string(c) + ", below 1");
  }
  ConvNetwork net("ConvNetwork(conv_stack)", Grid{dims, n}, channels.front());
  int slot = 0;
  for (std::size_t l = 1; l < channels.size(); ++l) {
    slot = net.add_conv(slot, channels[l], kernel, 1, padding);
    if (l + 1 < channels.size()) slot = net.add_activation(slot, activation);
  }
  net.finish({{"kind", "conv_stack"},
              {"dims", dims},
              {"n", n},
              {"channels", channels},
              {"kernel", kernel},
              {"activation", to_string(activation)},
              {"padding", to_string(padding)}});
  return net;
}

void ConvNetwork::initialize(std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  const auto uniform = [&engine](double bound) {
    const double u = static_cast<double>(engine() >> 11) * 0x1p-53;  // uniform in [0, 1)
    return bound * (2.0 * u - 1.0);
  };
  for (const ConvOp& op : ops_) {
    if (op.kind == ConvOpKind::kConv) {
      const Index fan_in = op.channels_in * op.geometry->taps();
      const double bound = 1.0 / std::sqrt(static_cast<double>(fan_in));
      for (Index k = 0; k < (fan_in + 1) * op.channels_out; ++k) {
        theta_[op.offset + k] = uniform(bound);
      }
    } else if (op.kind == ConvOpKind::kBatchNorm) {
      theta_.segment(op.offset, op.channels_out).setOnes();
      theta_.segment(op.offset + op.channels_out, op.channels_out).setZero();
    }
  }
}

bool ConvNetwork::has_batch_norm() const {
  for (const ConvOp& op : ops_) {
    if (op.kind == ConvOpKind::kBatchNorm) return true;
  }
  return false;
}

nlohmann::json ConvNetwork::describe() const {
  nlohmann::json j = options_;
  j["parameters"] = num_parameters_;
  j["input_dim"] = input_dim_;
  j["output_dim"] = output_dim_;
  return j;
}

void ConvNetwork::refuse_batch_norm(const std::string& member) const {
  if (has_batch_norm()) {
    throw Error("ConvNetwork::" + member +
                ": batch norm couples the samples, so per-sample Jacobians are not defined; the "
                "Jacobian rules (gn, hig, kfac, kfac-hig, lanczos-*) need batch_norm off");
  }
}

}  // namespace physgrad
