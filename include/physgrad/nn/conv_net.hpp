// ConvNetwork — convolutional networks on a line or square grid (plain stacks and phiml's U-net)
// as a Network: a tape of ops (k^d convolution, activation, batch norm, 2× down/up, concat).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "physgrad/nn/activation.hpp"
#include "physgrad/nn/conv_layers.hpp"
#include "physgrad/nn/network.hpp"
#include "physgrad/types.hpp"

namespace physgrad {

// The shape of phiml's u_net: inc = DoubleConv(in → filters); (levels − 1)× down (2× max-pool, or
// stride 2 in the first convolution) + DoubleConv(filters → filters); (levels − 1)× up (2×
// upsample, concat [skip, upsampled], DoubleConv(2·filters → filters)); a 1×1 convolution to
// out_channels. DoubleConv = (3^d conv → [batch norm] → activation) twice.
struct UNetOptions {
  int dims = 2;  // 1 (a line of n cells) or 2 (n×n grid)
  Index n = 64;  // cells per axis; must be divisible by 2^(levels-1)
  Index in_channels = 1, out_channels = 1;
  int levels = 4;
  Index filters = 16;
  Activation activation = Activation::kRelu;
  bool batch_norm = false;
  Padding padding = Padding::kZero;
  Downsample down = Downsample::kMaxPool;
  Upsample up = Upsample::kBilinear;
};

enum class ConvOpKind { kConv, kActivation, kBatchNorm, kMaxPool, kUpsample, kConcat };

// One op of the tape: reads slot `input` (and `skip` for a concat, whose channels come first),
// writes slot (own index + 1); slot 0 is the network's input.
struct ConvOp {
  ConvOpKind kind = ConvOpKind::kConv;
  int input = 0;
  int skip = -1;
  Index channels_in = 0, channels_out = 0;
  Grid grid_in, grid_out;
  int kernel = 1, stride = 1;
  Activation activation = Activation::kIdentity;
  Index offset = 0;  // conv: [vec(W) (channels_in·taps × channels_out), b]; BN: [γ, β]
  std::shared_ptr<const ConvGeometry> geometry;  // conv
  std::shared_ptr<const GridStencil> stencil;    // max-pool and upsample
};

// What forward() keeps: every slot's values (rows channel·cells + cell, one sample per column),
// max-pool choices and batch norm's normalized values and 1/σ per channel.
struct ConvNetworkCache final : NetworkCache {
  std::vector<Matrix> values;
  std::vector<std::vector<Index>> argmax;
  std::vector<Matrix> normalized;
  std::vector<Vector> inv_std;
};

// Threads over which ConvNetwork's convolutions split the samples of a batch (contiguous blocks,
// fixed by the count, so results are deterministic for a count and differ between counts only
// by the round-off of summing the gradient blocks). Process-wide; 1 by default; throws Error
// unless threads ≥ 1.
void set_conv_threads(int threads);
int conv_threads();

// Samples are columns; channel c at cell (i, j) is row c·n^d + i + n·j.
class ConvNetwork final : public Network {
 public:
  // phiml's u_net shape (see UNetOptions); throws Error on dims ∉ {1, 2}, levels < 1, n not
  // divisible by 2^(levels − 1), or channels/filters < 1.
  static ConvNetwork unet(const UNetOptions& options);
  // channels = {in, hidden…, out}: a k^d convolution between consecutive entries, `activation`
  // after each but the last.
  static ConvNetwork conv_stack(int dims, Index n, const std::vector<Index>& channels,
                                int kernel = 3, Activation activation = Activation::kRelu,
                                Padding padding = Padding::kZero);

  // Conv weights and biases from U(±1/√fan_in), fan_in = channels_in·taps, drawn in θ's order
  // with std::mt19937_64(seed); batch norm's γ = 1, β = 0.
  void initialize(std::uint64_t seed);
  // The architecture as JSON: kind, options, parameter count.
  nlohmann::json describe() const override;
  const std::vector<ConvOp>& ops() const { return ops_; }
  bool has_batch_norm() const;

  std::string name() const override { return name_; }
  Index input_dim() const override { return input_dim_; }
  Index output_dim() const override { return output_dim_; }
  Index num_parameters() const override { return num_parameters_; }
  const Vector& parameters() const override { return theta_; }
  Vector& parameters() override { return theta_; }

  std::unique_ptr<NetworkCache> new_cache() const override;
  using Network::forward;
  Matrix forward(const Matrix& x, NetworkCache& cache) const override;
  Vector backward(const NetworkCache& cache, const Matrix& gy) const override;
  // The per-sample members need samples that do not see each other: they throw Error when the
  // network has batch norm.
  using Network::per_sample_gradients;
  void per_sample_gradients(const NetworkCache& cache, const Matrix& gy,
                            StridedMatrixRef out) const override;
  Matrix per_sample_gram(const NetworkCache& cache,
                         const std::vector<Matrix>& cotangents) const override;
  Matrix per_sample_gram_columns(const NetworkCache& cache, const std::vector<Matrix>& cotangents,
                                 const std::vector<Index>& selected) const override;
  // The tangent of every slot propagated through the tape (forward mode).
  Matrix jvp(const NetworkCache& cache, Index batch, const Vector& v) const override;
  // Every conv layer as a dense layer at each output position p (KFC): input_gram =
  // Σ_{b,p} ā_bp ā_bpᵀ over the im2col patches with the bias's 1, cotangent_gram =
  // (1/P) Σ_{c,p} δ_cp δ_cpᵀ, θ blocks [vec(Wᵀ), b] (transposed); one reverse sweep per cotangent
  // matrix. Throws Error with batch norm.
  std::vector<DenseLayerFactors> dense_layer_factors(
      const NetworkCache& cache, const std::vector<Matrix>& cotangents) const override;

 private:
  ConvNetwork(std::string name, Grid grid, Index channels);
  // Builders: each appends an op reading `input` and returns the slot it writes.
  int add_conv(int input, Index channels_out, int kernel, int stride, Padding padding);
  int add_activation(int input, Activation activation);
  int add_batch_norm(int input);
  int add_max_pool(int input);
  int add_upsample(int input, Upsample mode, Padding padding);
  int add_concat(int skip, int input);
  void finish(nlohmann::json options);
  Index slot_rows(int slot) const;
  const ConvNetworkCache& checked_cache(const NetworkCache& cache) const;
  void refuse_batch_norm(const std::string& member) const;
  // ∇θ: summed into *total, or sample b's into row b of *rows; or, with `cotangent_grams` (one
  // matrix per op), Σ_{b,p} δ_bp δ_bpᵀ of each conv op's output cotangents added to its entry.
  void reverse(const ConvNetworkCache& cache, const Matrix& gy, Vector* total,
               StridedMatrixRef* rows, std::vector<Matrix>* cotangent_grams = nullptr) const;

  std::string name_;
  std::vector<ConvOp> ops_;
  std::vector<Index> slot_channels_;
  std::vector<Grid> slot_grids_;
  Index input_dim_ = 0, output_dim_ = 0, num_parameters_ = 0;
  nlohmann::json options_;
  Vector theta_;
};

}  // namespace physgrad
