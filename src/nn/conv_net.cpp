// ConvNetwork's forward pass and derivatives: one sweep over the tape of ops per member.
#include "physgrad/nn/conv_net.hpp"

#include <string>

#include "conv_ops.hpp"
#include "physgrad/error.hpp"

namespace physgrad {

std::unique_ptr<NetworkCache> ConvNetwork::new_cache() const {
  return std::make_unique<ConvNetworkCache>();
}

Matrix ConvNetwork::forward(const Matrix& x, NetworkCache& cache_base) const {
  auto* cache = dynamic_cast<ConvNetworkCache*>(&cache_base);
  if (cache == nullptr) throw Error("ConvNetwork: the cache comes from another kind of network");
  if (theta_.size() != num_parameters_) {
    throw Error("ConvNetwork: parameters() was resized to " + std::to_string(theta_.size()) +
                ", the network has " + std::to_string(num_parameters_));
  }
  if (x.rows() != input_dim_ || x.cols() < 1) {
    throw Error("ConvNetwork::forward: input x is " + std::to_string(x.rows()) + "x" +
                std::to_string(x.cols()) + ", expected " + std::to_string(input_dim_) +
                " rows and at least one column");
  }
  const std::size_t count = ops_.size();
  cache->values.resize(count + 1);
  cache->argmax.resize(count);
  cache->normalized.resize(count);
  cache->inv_std.resize(count);
  cache->values[0] = x;
  const Index batch = x.cols();
  for (std::size_t i = 0; i < count; ++i) {
    const ConvOp& op = ops_[i];
    const Matrix& in = cache->values[static_cast<std::size_t>(op.input)];
    Matrix& out = cache->values[i + 1];
    const Index rows_out = slot_rows(static_cast<int>(i + 1));
    switch (op.kind) {
      case ConvOpKind::kConv: {
        const Vector bias = conv_ops::conv_bias(theta_, op);
        conv_ops::conv_apply(op, in, conv_ops::conv_weight(theta_, op), &bias, false, out);
        break;
      }
      case ConvOpKind::kActivation:
        out.resize(in.rows(), batch);
        apply(op.activation, in.array(), out.array());
        break;
      case ConvOpKind::kBatchNorm:
        conv_ops::batch_norm_forward(op, theta_, in, out, cache->normalized[i], cache->inv_std[i]);
        break;
      case ConvOpKind::kMaxPool:
        out.resize(rows_out, batch);
        cache->argmax[i].resize(static_cast<std::size_t>(rows_out * batch));
        for (Index b = 0; b < batch; ++b) {
          op.stencil->max_pool(in.col(b).data(), op.channels_in, out.col(b).data(),
                               cache->argmax[i].data() + b * rows_out);
        }
        break;
      case ConvOpKind::kUpsample:
        out.resize(rows_out, batch);
        for (Index b = 0; b < batch; ++b) {
          op.stencil->apply(in.col(b).data(), op.channels_in, out.col(b).data());
        }
        break;
      case ConvOpKind::kConcat: {
        const Matrix& skip = cache->values[static_cast<std::size_t>(op.skip)];
        out.resize(rows_out, batch);
        out.topRows(skip.rows()) = skip;
        out.bottomRows(in.rows()) = in;
        break;
      }
    }
  }
  return cache->values.back();
}

const ConvNetworkCache& ConvNetwork::checked_cache(const NetworkCache& cache_base) const {
  const auto* cache = dynamic_cast<const ConvNetworkCache*>(&cache_base);
  if (cache == nullptr) throw Error("ConvNetwork: the cache comes from another kind of network");
  if (cache->values.size() != ops_.size() + 1 || cache->values[0].rows() != input_dim_) {
    throw Error("ConvNetwork: the cache holds " + std::to_string(cache->values.size()) +
                " slots; run forward(x, cache) on this network first");
  }
  if (theta_.size() != num_parameters_) {
    throw Error("ConvNetwork: parameters() was resized to " + std::to_string(theta_.size()) +
                ", the network has " + std::to_string(num_parameters_));
  }
  return *cache;
}

}  // namespace physgrad
