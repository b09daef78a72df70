// Conv ops — the batched steps of ConvNetwork's tape that need more than a line: convolution
// sample by sample (im2col + GEMM, y = P(x) W + 1 bᵀ) and batch norm y = γ (x − μ)/√(σ² + ε) + β.
#pragma once

#include <functional>

#include "physgrad/nn/conv_net.hpp"

namespace physgrad::conv_ops {

using ConstMap = Eigen::Map<const Matrix>;
using MutMap = Eigen::Map<Matrix>;

inline ConstMap conv_weight(const Vector& theta, const ConvOp& op) {
  return ConstMap(theta.data() + op.offset, op.channels_in * op.geometry->taps(), op.channels_out);
}
inline Index conv_bias_offset(const ConvOp& op) {
  return op.offset + op.channels_in * op.geometry->taps() * op.channels_out;
}
inline Eigen::Map<const Vector> conv_bias(const Vector& theta, const ConvOp& op) {
  return Eigen::Map<const Vector>(theta.data() + conv_bias_offset(op), op.channels_out);
}

// C (m × n) = α op(A) op(B) + β C, column-major, through the BLAS (cblas_dgemm); `ta`/`tb`
// transpose A/B.
void conv_gemm(bool ta, bool tb, Index m, Index n, Index k, double alpha, const double* a,
               Index lda, const double* b, Index ldb, double beta, double* c, Index ldc);

// Runs work(begin, end, worker) on conv_threads() contiguous blocks of [0, count), one per worker
// (fewer when count is smaller), the last in the calling thread; returns the number of workers.
int for_sample_blocks(Index count, const std::function<void(Index, Index, int)>& work);

// y = conv(x; W, b) sample by sample; with `add`, y += conv(x; W) (+ b when given).
void conv_apply(const ConvOp& op, const Matrix& x, ConstMap w, const Vector* bias, bool add,
                Matrix& y);
// Σ_b Σ_p ā_bp ā_bpᵀ over the patches ā = [patch; 1] of every sample of x ((fan_in + 1)²).
Matrix conv_input_gram(const ConvOp& op, const Matrix& x);
// gram (channels_out²) += Σ_b Σ_p δ_bp δ_bpᵀ, δ_bp row p of sample b's cotangent G_b (cells_out ×
// channels_out): Σ_b G_bᵀ G_b.
void conv_cotangent_gram_add(const ConvOp& op, const Matrix& g, Matrix& gram);
void batch_norm_forward(const ConvOp& op, const Vector& theta, const Matrix& x, Matrix& y,
                        Matrix& normalized, Vector& inv_std);
// Adds ∂/∂x of the batch norm to gx and its [dγ, dβ] to grad (op.offset on).
void batch_norm_backward(const ConvOp& op, const Vector& theta, const Matrix& g,
                         const Matrix& normalized, const Vector& inv_std, Matrix& gx, Vector& grad);
// Sizes m to rows × cols of zeros unless it has that shape already.
inline void ensure_zero(Matrix& m, Index rows, Index cols) {
  if (m.rows() != rows || m.cols() != cols) m = Matrix::Zero(rows, cols);
}

}  // namespace physgrad::conv_ops
