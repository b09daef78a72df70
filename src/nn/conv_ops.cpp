#include "conv_ops.hpp"

#include <cblas.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {
std::atomic<int> conv_thread_count{1};
}  // namespace

void set_conv_threads(int threads) {
  if (threads < 1)
    throw Error("set_conv_threads: threads " + std::to_string(threads) + " is below 1");
  conv_thread_count = threads;
}

int conv_threads() { return conv_thread_count; }

}  // namespace physgrad

namespace physgrad::conv_ops {

void conv_gemm(bool ta, bool tb, Index m, Index n, Index k, double alpha, const double* a,
               Index lda, const double* b, Index ldb, double beta, double* c, Index ldc) {
  const auto dim = [](Index value) { return static_cast<blasint>(value); };
  cblas_dgemm(CblasColMajor, ta ? CblasTrans : CblasNoTrans, tb ? CblasTrans : CblasNoTrans,
              dim(m), dim(n), dim(k), alpha, a, dim(lda), b, dim(ldb), beta, c, dim(ldc));
}

int for_sample_blocks(Index count, const std::function<void(Index, Index, int)>& work) {
  const int workers = static_cast<int>(std::min<Index>(conv_threads(), std::max<Index>(count, 1)));
  std::vector<std::thread> threads;
  const auto block = [&](int w) { return count * w / workers; };
  for (int w = 0; w + 1 < workers; ++w) {
    threads.emplace_back([&work, &block, w] { work(block(w), block(w + 1), w); });
  }
  work(block(workers - 1), count, workers - 1);
  for (auto& t : threads) t.join();
  return workers;
}

void conv_apply(const ConvOp& op, const Matrix& x, ConstMap w, const Vector* bias, bool add,
                Matrix& y) {
  const Index batch = x.cols();
  const Index cells_out = op.grid_out.cells();
  if (!add) y.resize(cells_out * op.channels_out, batch);
  for_sample_blocks(batch, [&](Index begin, Index end, int) {
    Matrix patches;
    for (Index b = begin; b < end; ++b) {
      op.geometry->im2col(x.col(b).data(), op.channels_in, patches);
      MutMap yb(y.col(b).data(), cells_out, op.channels_out);
      conv_gemm(false, false, cells_out, op.channels_out, patches.cols(), 1.0, patches.data(),
                cells_out, w.data(), w.rows(), add ? 1.0 : 0.0, yb.data(), cells_out);
      if (bias != nullptr) yb.rowwise() += bias->transpose();
    }
  });
}

void batch_norm_forward(const ConvOp& op, const Vector& theta, const Matrix& x, Matrix& y,
                        Matrix& normalized, Vector& inv_std) {
  constexpr double kEps = 1e-5;
  const Index cells = op.grid_in.cells();
  const Index batch = x.cols();
  const auto count = static_cast<double>(cells * batch);
  normalized.resize(x.rows(), batch);
  inv_std.resize(op.channels_out);
  y.resize(x.rows(), batch);
  for (Index c = 0; c < op.channels_out; ++c) {
    const auto block = x.middleRows(c * cells, cells).array();
    const double mean = block.sum() / count;
    const double var = (block - mean).square().sum() / count;
    inv_std[c] = 1.0 / std::sqrt(var + kEps);
    normalized.middleRows(c * cells, cells).array() = (block - mean) * inv_std[c];
    y.middleRows(c * cells, cells).array() =
        theta[op.offset + c] * normalized.middleRows(c * cells, cells).array() +
        theta[op.offset + op.channels_out + c];
  }
}

void batch_norm_backward(const ConvOp& op, const Vector& theta, const Matrix& g,
                         const Matrix& normalized, const Vector& inv_std, Matrix& gx,
                         Vector& grad) {
  const Index cells = op.grid_in.cells();
  const auto count = static_cast<double>(cells * g.cols());
  for (Index c = 0; c < op.channels_out; ++c) {
    const auto gc = g.middleRows(c * cells, cells).array();
    const auto xh = normalized.middleRows(c * cells, cells).array();
    const double sum_g = gc.sum();
    const double sum_gx = (gc * xh).sum();
    grad[op.offset + c] += sum_gx;
    grad[op.offset + op.channels_out + c] += sum_g;
    gx.middleRows(c * cells, cells).array() +=
        theta[op.offset + c] * inv_std[c] * (gc - sum_g / count - xh * (sum_gx / count));
  }
}

}  // namespace physgrad::conv_ops
