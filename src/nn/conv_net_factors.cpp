// ConvNetwork's Kronecker factors (KFC): each conv layer as a dense layer applied at every output
// position, A = Σ_{b,p} ā_bp ā_bpᵀ over the im2col patches, S = (1/P) Σ_{c,p} δ_cp δ_cpᵀ.
#include <cblas.h>

#include <string>
#include <vector>

#include "conv_ops.hpp"
#include "physgrad/error.hpp"
#include "physgrad/nn/conv_net.hpp"

namespace physgrad {

namespace {

// The lower triangle of c (n × n, leading dimension ldc) += aᵀ a for a (k × n, column-major,
// leading dimension lda).
void conv_factor_syrk(Index n, Index k, const double* a, Index lda, double* c, Index ldc) {
  const auto dim = [](Index value) { return static_cast<blasint>(value); };
  cblas_dsyrk(CblasColMajor, CblasLower, CblasTrans, dim(n), dim(k), 1.0, a, dim(lda), 1.0, c,
              dim(ldc));
}

// Copies the lower triangle onto the upper one.
void conv_factor_symmetrize(Matrix& m) {
  m.triangularView<Eigen::StrictlyUpper>() = m.transpose();
}

// Σ over the workers' partial sums, in worker order (deterministic for a thread count).
Matrix conv_factor_sum(const std::vector<Matrix>& partial, int workers) {
  Matrix total = partial[0];
  for (int w = 1; w < workers; ++w) total += partial[static_cast<std::size_t>(w)];
  return total;
}

}  // namespace

namespace conv_ops {

Matrix conv_input_gram(const ConvOp& op, const Matrix& x) {
  const Index fan_in = op.channels_in * op.geometry->taps();
  const Index cells_out = op.grid_out.cells();
  std::vector<Matrix> partial(static_cast<std::size_t>(conv_threads()));
  const int workers = for_sample_blocks(x.cols(), [&](Index begin, Index end, int w) {
    Matrix& sum = partial[static_cast<std::size_t>(w)];
    sum = Matrix::Zero(fan_in + 1, fan_in + 1);
    Matrix patches;
    for (Index b = begin; b < end; ++b) {
      op.geometry->im2col(x.col(b).data(), op.channels_in, patches);
      conv_factor_syrk(fan_in, cells_out, patches.data(), cells_out, sum.data(), fan_in + 1);
      sum.row(fan_in).head(fan_in) += patches.colwise().sum();  // Σ_p patch_p · 1
    }
    sum(fan_in, fan_in) = static_cast<double>((end - begin) * cells_out);
  });
  Matrix gram = conv_factor_sum(partial, workers);
  conv_factor_symmetrize(gram);
  return gram;
}

void conv_cotangent_gram_add(const ConvOp& op, const Matrix& g, Matrix& gram) {
  const Index cells_out = op.grid_out.cells();
  const Index out = op.channels_out;
  std::vector<Matrix> partial(static_cast<std::size_t>(conv_threads()));
  const int workers = for_sample_blocks(g.cols(), [&](Index begin, Index end, int w) {
    Matrix& sum = partial[static_cast<std::size_t>(w)];
    sum = Matrix::Zero(out, out);
    for (Index b = begin; b < end; ++b) {
      conv_factor_syrk(out, cells_out, g.col(b).data(), cells_out, sum.data(), out);
    }
  });
  gram += conv_factor_sum(partial, workers);  // lower triangle only; symmetrized by the caller
}

}  // namespace conv_ops

std::vector<DenseLayerFactors> ConvNetwork::dense_layer_factors(
    const NetworkCache& cache, const std::vector<Matrix>& cotangents) const {
  refuse_batch_norm("dense_layer_factors");
  const ConvNetworkCache& own = checked_cache(cache);
  std::vector<Matrix> grams(ops_.size());
  std::vector<DenseLayerFactors> layers;
  for (std::size_t i = 0; i < ops_.size(); ++i) {
    const ConvOp& op = ops_[i];
    if (op.kind != ConvOpKind::kConv) continue;
    grams[i] = Matrix::Zero(op.channels_out, op.channels_out);
    DenseLayerFactors f;
    f.offset = op.offset;
    f.outputs = op.channels_out;
    f.inputs = op.channels_in * op.geometry->taps();
    f.transposed = true;
    f.input_gram = conv_ops::conv_input_gram(op, own.values[static_cast<std::size_t>(op.input)]);
    layers.push_back(std::move(f));
  }
  for (const Matrix& gy : cotangents) reverse(own, gy, nullptr, nullptr, &grams);
  std::size_t l = 0;
  for (std::size_t i = 0; i < ops_.size(); ++i) {
    if (ops_[i].kind != ConvOpKind::kConv) continue;
    conv_factor_symmetrize(grams[i]);
    layers[l++].cotangent_gram =
        grams[i] / static_cast<double>(ops_[i].grid_out.cells());  // (1/P) Σ_p
  }
  return layers;
}

}  // namespace physgrad
