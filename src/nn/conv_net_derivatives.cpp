// ConvNetwork's derivatives: the reverse sweep (∇θ summed or per sample) and the forward-mode
// tangent sweep ∂f/∂θ·v over the tape of ops.
#include <string>
#include <vector>

#include "conv_ops.hpp"
#include "physgrad/error.hpp"
#include "physgrad/nn/conv_net.hpp"

namespace physgrad {

namespace {

// Sample b of a conv op in reverse: its ∇W, ∇b (summed into `total` or written to `row`) and,
// when gx is given, its input cotangent.
void conv_sample_reverse(const ConvOp& op, const Vector& theta, const Matrix& x, const Matrix& g,
                         Index b, Matrix& patches, Vector* total, StridedMatrixRef* rows,
                         Matrix* gx) {
  const Index cells_out = op.grid_out.cells();
  const Index fan_in = op.channels_in * op.geometry->taps();
  const conv_ops::ConstMap gb(g.col(b).data(), cells_out, op.channels_out);
  const Index bias_at = conv_ops::conv_bias_offset(op);
  if (total != nullptr || rows != nullptr) {
    op.geometry->im2col(x.col(b).data(), op.channels_in, patches);
  }
  if (total != nullptr) {
    conv_ops::conv_gemm(true, false, fan_in, op.channels_out, cells_out, 1.0, patches.data(),
                        cells_out, gb.data(), cells_out, 1.0, total->data() + op.offset, fan_in);
    total->segment(bias_at, op.channels_out) += gb.colwise().sum().transpose();
  } else if (rows != nullptr) {
    const Matrix dw = patches.transpose() * gb;
    rows->row(b).segment(op.offset, dw.size()) = dw.reshaped().transpose();
    rows->row(b).segment(bias_at, op.channels_out) = gb.colwise().sum();
  }
  if (gx != nullptr) {
    patches.resize(cells_out, fan_in);  // reused for ∂/∂patches = G Wᵀ
    conv_ops::conv_gemm(false, true, cells_out, fan_in, op.channels_out, 1.0, gb.data(), cells_out,
                        theta.data() + op.offset, fan_in, 0.0, patches.data(), cells_out);
    op.geometry->col2im_add(patches, op.channels_in, gx->col(b).data());
  }
}

// A conv op in reverse over the batch, the samples split over the conv threads; each worker sums
// its samples' ∇θ into its own vector, added to *total in worker order.
void conv_reverse(const ConvOp& op, const Vector& theta, const Matrix& x, const Matrix& g,
                  Vector* total, StridedMatrixRef* rows, Matrix* gx) {
  const int most = conv_threads();
  std::vector<Vector> partial(static_cast<std::size_t>(total != nullptr ? most : 0));
  const int workers = conv_ops::for_sample_blocks(x.cols(), [&](Index begin, Index end, int w) {
    Vector* sum = nullptr;
    if (total != nullptr) {
      partial[static_cast<std::size_t>(w)] = Vector::Zero(total->size());
      sum = &partial[static_cast<std::size_t>(w)];
    }
    Matrix patches;
    for (Index b = begin; b < end; ++b) {
      conv_sample_reverse(op, theta, x, g, b, patches, sum, rows, gx);
    }
  });
  if (total == nullptr) return;
  const Index first = op.offset;
  const Index size = conv_ops::conv_bias_offset(op) + op.channels_out - first;
  for (int w = 0; w < workers; ++w) {
    total->segment(first, size) += partial[static_cast<std::size_t>(w)].segment(first, size);
  }
}

}  // namespace

void ConvNetwork::reverse(const ConvNetworkCache& cache, const Matrix& gy, Vector* total,
                          StridedMatrixRef* rows, std::vector<Matrix>* cotangent_grams) const {
  const Index batch = cache.values[0].cols();
  if (gy.rows() != output_dim_ || gy.cols() != batch) {
    throw Error("ConvNetwork: gy is " + std::to_string(gy.rows()) + "x" +
                std::to_string(gy.cols()) + ", expected " + std::to_string(output_dim_) + "x" +
                std::to_string(batch));
  }
  std::vector<Matrix> grads(ops_.size() + 1);
  grads.back() = gy;
  for (std::size_t i = ops_.size(); i-- > 0;) {
    const ConvOp& op = ops_[i];
    Matrix& g = grads[i + 1];
    if (g.size() == 0) continue;  // the slot does not reach the output
    const auto in_slot = static_cast<std::size_t>(op.input);
    const Matrix& x = cache.values[in_slot];
    Matrix& gx = grads[in_slot];
    const bool need_gx = in_slot != 0;
    conv_ops::ensure_zero(gx, x.rows(), batch);
    switch (op.kind) {
      case ConvOpKind::kConv:
        if (cotangent_grams != nullptr) {
          conv_ops::conv_cotangent_gram_add(op, g, (*cotangent_grams)[i]);
          if (need_gx) conv_reverse(op, theta_, x, g, nullptr, nullptr, &gx);
        } else {
          conv_reverse(op, theta_, x, g, total, rows, need_gx ? &gx : nullptr);
        }
        break;
      case ConvOpKind::kActivation: {
        Eigen::ArrayXXd slope(x.rows(), batch);
        derivative(op.activation, x.array(), slope);
        gx.array() += g.array() * slope;
        break;
      }
      case ConvOpKind::kBatchNorm:
        conv_ops::batch_norm_backward(op, theta_, g, cache.normalized[i], cache.inv_std[i], gx,
                                      *total);
        break;
      case ConvOpKind::kMaxPool: {
        const auto& argmax = cache.argmax[i];
        const Index rows_out = g.rows();
        const Index cells_in = op.grid_in.cells();
        const Index cells_out = op.grid_out.cells();
        for (Index b = 0; b < batch; ++b) {
          for (Index r = 0; r < rows_out; ++r) {
            const Index c = r / cells_out;
            gx(c * cells_in + argmax[static_cast<std::size_t>(b * rows_out + r)], b) += g(r, b);
          }
        }
        break;
      }
      case ConvOpKind::kUpsample:
        for (Index b = 0; b < batch; ++b) {
          op.stencil->adjoint_add(g.col(b).data(), op.channels_in, gx.col(b).data());
        }
        break;
      case ConvOpKind::kConcat: {
        const auto skip_slot = static_cast<std::size_t>(op.skip);
        const Index skip_rows = cache.values[skip_slot].rows();
        if (skip_slot != 0) {
          conv_ops::ensure_zero(grads[skip_slot], skip_rows, batch);
          grads[skip_slot] += g.topRows(skip_rows);
        }
        gx += g.bottomRows(x.rows());
        break;
      }
    }
    g.resize(0, 0);  // every reader of slot i + 1 comes later on the tape, so it is done
  }
}

Vector ConvNetwork::backward(const NetworkCache& cache, const Matrix& gy) const {
  const ConvNetworkCache& own = checked_cache(cache);
  Vector grad = Vector::Zero(num_parameters_);
  reverse(own, gy, &grad, nullptr);
  return grad;
}

void ConvNetwork::per_sample_gradients(const NetworkCache& cache, const Matrix& gy,
                                       StridedMatrixRef out) const {
  refuse_batch_norm("per_sample_gradients");
  const ConvNetworkCache& own = checked_cache(cache);
  const Index batch = own.values[0].cols();
  if (out.rows() != batch || out.cols() != num_parameters_) {
    throw Error("ConvNetwork::per_sample_gradients: out is " + std::to_string(out.rows()) + "x" +
                std::to_string(out.cols()) + ", expected " + std::to_string(batch) + "x" +
                std::to_string(num_parameters_));
  }
  reverse(own, gy, nullptr, &out);
}

Matrix ConvNetwork::per_sample_gram(const NetworkCache& cache,
                                    const std::vector<Matrix>& cotangents) const {
  refuse_batch_norm("per_sample_gram");
  return Network::per_sample_gram(cache, cotangents);
}

Matrix ConvNetwork::per_sample_gram_columns(const NetworkCache& cache,
                                            const std::vector<Matrix>& cotangents,
                                            const std::vector<Index>& selected) const {
  refuse_batch_norm("per_sample_gram_columns");
  return Network::per_sample_gram_columns(cache, cotangents, selected);
}

Matrix ConvNetwork::jvp(const NetworkCache& cache, Index batch, const Vector& v) const {
  refuse_batch_norm("jvp");
  const ConvNetworkCache& own = checked_cache(cache);
  if (batch != own.values[0].cols() || v.size() != num_parameters_) {
    throw Error("ConvNetwork::jvp: batch " + std::to_string(batch) + " and v of " +
                std::to_string(v.size()) + " entries, expected " +
                std::to_string(own.values[0].cols()) + " and " + std::to_string(num_parameters_));
  }
  std::vector<Matrix> tangents(ops_.size() + 1);
  tangents[0] = Matrix::Zero(input_dim_, batch);
  for (std::size_t i = 0; i < ops_.size(); ++i) {
    const ConvOp& op = ops_[i];
    const auto in_slot = static_cast<std::size_t>(op.input);
    const Matrix& dx = tangents[in_slot];
    Matrix& dy = tangents[i + 1];
    switch (op.kind) {
      case ConvOpKind::kConv: {
        const Vector dbias = conv_ops::conv_bias(v, op);
        conv_ops::conv_apply(op, own.values[in_slot], conv_ops::conv_weight(v, op), &dbias, false,
                             dy);
        if (in_slot != 0) {
          conv_ops::conv_apply(op, dx, conv_ops::conv_weight(theta_, op), nullptr, true, dy);
        }
        break;
      }
      case ConvOpKind::kActivation: {
        Eigen::ArrayXXd slope(dx.rows(), batch);
        derivative(op.activation, own.values[in_slot].array(), slope);
        dy = (dx.array() * slope).matrix();
        break;
      }
      case ConvOpKind::kBatchNorm:
        break;  // refused above
      case ConvOpKind::kMaxPool: {
        const auto& argmax = own.argmax[i];
        const Index rows_out = own.values[i + 1].rows();
        const Index cells_in = op.grid_in.cells();
        const Index cells_out = op.grid_out.cells();
        dy.resize(rows_out, batch);
        for (Index b = 0; b < batch; ++b) {
          for (Index r = 0; r < rows_out; ++r) {
            const Index c = r / cells_out;
            dy(r, b) = dx(c * cells_in + argmax[static_cast<std::size_t>(b * rows_out + r)], b);
          }
        }
        break;
      }
      case ConvOpKind::kUpsample:
        dy.resize(own.values[i + 1].rows(), batch);
        for (Index b = 0; b < batch; ++b) {
          op.stencil->apply(dx.col(b).data(), op.channels_in, dy.col(b).data());
        }
        break;
      case ConvOpKind::kConcat: {
        const Matrix& dskip = tangents[static_cast<std::size_t>(op.skip)];
        dy.resize(dskip.rows() + dx.rows(), batch);
        dy.topRows(dskip.rows()) = dskip;
        dy.bottomRows(dx.rows()) = dx;
        break;
      }
    }
  }
  return tangents.back();
}

}  // namespace physgrad
