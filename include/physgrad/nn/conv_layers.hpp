// Conv layers — ConvNetwork's kernels on one sample (cells × channels): convolution as im2col,
// y[o, c'] = b[c'] + Σ_{c,t} W[c·K + t, c'] x[s·o + d_t, c]; 2× max-pool and 2× up-sampling.
#pragma once

#include <string>
#include <vector>

#include "physgrad/types.hpp"

namespace physgrad {

// Outside the grid: zero (kZero) or wrapped around (kPeriodic).
enum class Padding { kZero, kPeriodic };
// Halving the cells per axis: 2× max-pool, or the first convolution of the block with stride 2.
enum class Downsample { kMaxPool, kStrided };
// Doubling the cells per axis: copy (kNearest) or linear interpolation with weights ¾, ¼ at the
// half-pixel positions (kBilinear).
enum class Upsample { kNearest, kBilinear };

std::string to_string(Padding padding);        // "zero", "periodic"
std::string to_string(Downsample downsample);  // "maxpool", "strided"
std::string to_string(Upsample upsample);      // "nearest", "bilinear"

// A grid of n cells per axis in `dims` dimensions; cell (i, j) is i + n·j.
struct Grid {
  int dims = 2;
  Index n = 1;
  Index cells() const { return dims == 1 ? n : n * n; }
};

// A k^dims-tap convolution with stride s from `in` to the grid of n / s cells per axis. For each
// output cell o and tap t, table[t·cells_out + o] is the input cell read, or −1 outside the grid
// (zero padding). One sample's field is a cells × channels column-major matrix.
class ConvGeometry {
 public:
  ConvGeometry() = default;
  ConvGeometry(Grid in, int kernel, int stride, Padding padding);

  Grid in() const { return in_; }
  Grid out() const { return out_; }
  Index taps() const { return taps_; }
  // patches (cells_out × channels·taps) column c·taps + t = input channel c read at tap t.
  void im2col(const double* x, Index channels, Matrix& patches) const;
  // dx (cells_in × channels) += the adjoint of im2col applied to dpatches.
  void col2im_add(const Matrix& dpatches, Index channels, double* dx) const;

 private:
  Grid in_, out_;
  Index taps_ = 1;
  std::vector<Index> table_;
};

// A fixed linear map between grids, out[o] = Σ_k weight·in[cell] over the entries of o
// (at most `width` each), used by up-sampling; pooling uses the cells of each window.
class GridStencil {
 public:
  GridStencil() = default;
  static GridStencil upsample(Grid in, Upsample mode, Padding padding);
  static GridStencil pool_windows(Grid in);  // the 2^dims cells of each window, weight 1

  Grid in() const { return in_; }
  Grid out() const { return out_; }
  // y (cells_out × channels) = the map applied to x (cells_in × channels), channel by channel.
  void apply(const double* x, Index channels, double* y) const;
  // dx (cells_in × channels) += the adjoint applied to dy (cells_out × channels).
  void adjoint_add(const double* dy, Index channels, double* dx) const;
  // y = max over each window; argmax receives the chosen input cell per output entry.
  void max_pool(const double* x, Index channels, double* y, Index* argmax) const;

 private:
  Grid in_, out_;
  Index width_ = 1;
  std::vector<Index> cells_;     // cells_[o·width + k]
  std::vector<double> weights_;  // weights_[o·width + k]
};

}  // namespace physgrad
