#include "physgrad/nn/conv_layers.hpp"

#include <utility>

#include "physgrad/error.hpp"

namespace physgrad {

std::string to_string(Padding padding) { return padding == Padding::kZero ? "zero" : "periodic"; }
std::string to_string(Downsample downsample) {
  return downsample == Downsample::kMaxPool ? "maxpool" : "strided";
}
std::string to_string(Upsample upsample) {
  return upsample == Upsample::kNearest ? "nearest" : "bilinear";
}

namespace {

// The entries (cell, weight) of output index o along one axis of n input cells.
using AxisEntries = std::vector<std::pair<Index, double>>;

std::vector<AxisEntries> upsample_axis(Index n, Upsample mode, Padding padding) {
  std::vector<AxisEntries> axis(static_cast<std::size_t>(2 * n));
  for (Index o = 0; o < 2 * n; ++o) {
    const Index i = o / 2;
    auto& entries = axis[static_cast<std::size_t>(o)];
    if (mode == Upsample::kNearest) {
      entries.emplace_back(i, 1.0);
      continue;
    }
    Index other = (o % 2 == 0) ? i - 1 : i + 1;
    if (other < 0 || other >= n) {
      other = padding == Padding::kPeriodic ? (other + n) % n : i;  // wrap, or hold the edge
    }
    entries.emplace_back(i, 0.75);
    entries.emplace_back(other, 0.25);
  }
  return axis;
}

}  // namespace

ConvGeometry::ConvGeometry(Grid in, int kernel, int stride, Padding padding) : in_(in) {
  out_ = Grid{in.dims, in.n / stride};
  const Index k = kernel;
  const Index pad = (k - 1) / 2;
  taps_ = in.dims == 1 ? k : k * k;
  const Index cells_out = out_.cells();
  table_.assign(static_cast<std::size_t>(taps_ * cells_out), -1);
  const auto coordinate = [&](Index o, Index d) -> Index {
    Index c = stride * o + d - pad;
    if (padding == Padding::kPeriodic) return ((c % in.n) + in.n) % in.n;
    return (c < 0 || c >= in.n) ? -1 : c;
  };
  const Index kj = in.dims == 1 ? 1 : k;
  const Index nj = in.dims == 1 ? 1 : out_.n;
  for (Index tj = 0; tj < kj; ++tj) {
    for (Index ti = 0; ti < k; ++ti) {
      const Index t = ti + k * tj;
      for (Index oj = 0; oj < nj; ++oj) {
        const Index cj = in.dims == 1 ? 0 : coordinate(oj, tj);
        for (Index oi = 0; oi < out_.n; ++oi) {
          const Index ci = coordinate(oi, ti);
          const Index o = oi + out_.n * oj;
          table_[static_cast<std::size_t>(t * cells_out + o)] =
              (ci < 0 || cj < 0) ? -1 : ci + in.n * cj;
        }
      }
    }
  }
}

void ConvGeometry::im2col(const double* x, Index channels, Matrix& patches) const {
  const Index cells_out = out_.cells();
  const Index cells_in = in_.cells();
  patches.resize(cells_out, channels * taps_);
  for (Index c = 0; c < channels; ++c) {
    const double* xc = x + c * cells_in;
    for (Index t = 0; t < taps_; ++t) {
      const Index* tab = table_.data() + t * cells_out;
      double* col = patches.col(c * taps_ + t).data();
      for (Index o = 0; o < cells_out; ++o) col[o] = tab[o] >= 0 ? xc[tab[o]] : 0.0;
    }
  }
}

void ConvGeometry::col2im_add(const Matrix& dpatches, Index channels, double* dx) const {
  const Index cells_out = out_.cells();
  const Index cells_in = in_.cells();
  for (Index c = 0; c < channels; ++c) {
    double* dxc = dx + c * cells_in;
    for (Index t = 0; t < taps_; ++t) {
      const Index* tab = table_.data() + t * cells_out;
      const double* col = dpatches.col(c * taps_ + t).data();
      for (Index o = 0; o < cells_out; ++o) {
        if (tab[o] >= 0) dxc[tab[o]] += col[o];
      }
    }
  }
}

GridStencil GridStencil::upsample(Grid in, Upsample mode, Padding padding) {
  GridStencil s;
  s.in_ = in;
  s.out_ = Grid{in.dims, 2 * in.n};
  const auto axis = upsample_axis(in.n, mode, padding);
  const Index per_axis = mode == Upsample::kNearest ? 1 : 2;
  s.width_ = in.dims == 1 ? per_axis : per_axis * per_axis;
  const Index nj = in.dims == 1 ? 1 : s.out_.n;
  for (Index oj = 0; oj < nj; ++oj) {
    for (Index oi = 0; oi < s.out_.n; ++oi) {
      for (const auto& [ci, wi] : axis[static_cast<std::size_t>(oi)]) {
        if (in.dims == 1) {
          s.cells_.push_back(ci);
          s.weights_.push_back(wi);
          continue;
        }
        for (const auto& [cj, wj] : axis[static_cast<std::size_t>(oj)]) {
          s.cells_.push_back(ci + in.n * cj);
          s.weights_.push_back(wi * wj);
        }
      }
    }
  }
  return s;
}

GridStencil GridStencil::pool_windows(Grid in) {
  GridStencil s;
  s.in_ = in;
  s.out_ = Grid{in.dims, in.n / 2};
  s.width_ = in.dims == 1 ? 2 : 4;
  const Index nj = in.dims == 1 ? 1 : s.out_.n;
  for (Index oj = 0; oj < nj; ++oj) {
    for (Index oi = 0; oi < s.out_.n; ++oi) {
      for (Index b = 0; b < (in.dims == 1 ? 1 : 2); ++b) {
        for (Index a = 0; a < 2; ++a) {
          s.cells_.push_back(2 * oi + a + (in.dims == 1 ? 0 : in.n * (2 * oj + b)));
          s.weights_.push_back(1.0);
        }
      }
    }
  }
  return s;
}

void GridStencil::apply(const double* x, Index channels, double* y) const {
  const Index cells_out = out_.cells();
  const Index cells_in = in_.cells();
  for (Index c = 0; c < channels; ++c) {
    const double* xc = x + c * cells_in;
    double* yc = y + c * cells_out;
    for (Index o = 0; o < cells_out; ++o) {
      double sum = 0.0;
      for (Index k = o * width_; k < (o + 1) * width_; ++k) {
        sum += weights_[static_cast<std::size_t>(k)] * xc[cells_[static_cast<std::size_t>(k)]];
      }
      yc[o] = sum;
    }
  }
}

void GridStencil::adjoint_add(const double* dy, Index channels, double* dx) const {
  const Index cells_out = out_.cells();
  const Index cells_in = in_.cells();
  for (Index c = 0; c < channels; ++c) {
    double* dxc = dx + c * cells_in;
    const double* dyc = dy + c * cells_out;
    for (Index o = 0; o < cells_out; ++o) {
      for (Index k = o * width_; k < (o + 1) * width_; ++k) {
        dxc[cells_[static_cast<std::size_t>(k)]] += weights_[static_cast<std::size_t>(k)] * dyc[o];
      }
    }
  }
}

void GridStencil::max_pool(const double* x, Index channels, double* y, Index* argmax) const {
  const Index cells_out = out_.cells();
  const Index cells_in = in_.cells();
  for (Index c = 0; c < channels; ++c) {
    const double* xc = x + c * cells_in;
    for (Index o = 0; o < cells_out; ++o) {
      Index best = cells_[static_cast<std::size_t>(o * width_)];
      for (Index k = o * width_ + 1; k < (o + 1) * width_; ++k) {
        const Index cell = cells_[static_cast<std::size_t>(k)];
        if (xc[cell] > xc[best]) best = cell;
      }
      y[c * cells_out + o] = xc[best];
      argmax[c * cells_out + o] = best;
    }
  }
}

}  // namespace physgrad
