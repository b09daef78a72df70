#include "physgrad/physics/heat_diffusion.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <sstream>
#include <string>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wconversion"
#include <unsupported/Eigen/FFT>
#pragma GCC diagnostic pop

#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/stop.hpp"

namespace physgrad {

namespace {

using Complex = std::complex<double>;
using ComplexMatrix = Eigen::Matrix<Complex, Eigen::Dynamic, Eigen::Dynamic>;
using Fft = Eigen::FFT<double>;

// 1-D DFT (forward, or inverse with the 1/n factor) of every column of `a`.
ComplexMatrix transform_columns(Fft& fft, const ComplexMatrix& a, bool inverse) {
  ComplexMatrix out(a.rows(), a.cols());
  for (Index j = 0; j < a.cols(); ++j) {
    if (inverse) {
      fft.inv(out.col(j).data(), a.col(j).data(), a.rows());
    } else {
      fft.fwd(out.col(j).data(), a.col(j).data(), a.rows());
    }
  }
  return out;
}

// DFT of one field held as n×1 (1-D) or n×n (2-D, entry (i, j) = cell i + n·j).
ComplexMatrix transform(Fft& fft, const ComplexMatrix& field, bool inverse) {
  const ComplexMatrix along_i = transform_columns(fft, field, inverse);
  if (field.cols() == 1) return along_i;
  return transform_columns(fft, along_i.transpose(), inverse).transpose();
}

// numpy fftfreq(n)[i]: i/n for i < (n+1)/2, else (i − n)/n.
double fftfreq(Index i, Index n) {
  return static_cast<double>(2 * i < n ? i : i - n) / static_cast<double>(n);
}

// ½·exp(−½(a/scale)²), with a non-finite value (0/0) counted as 0.
double likelihood(double a, double scale) {
  const double ratio = a / scale;
  const double value = 0.5 * std::exp(-0.5 * ratio * ratio);
  return std::isfinite(value) ? value : 0.0;
}

constexpr double kMaxLogGain = 88;  // ⌊ln(largest float)⌋

}  // namespace

HeatDiffusion::HeatDiffusion(HeatConfig config) : config_(config) {
  require(config.n >= 1, "heat_diffusion", "n must be ≥ 1", static_cast<double>(config.n));
  require(config.dims == 1 || config.dims == 2, "heat_diffusion", "dims must be 1 or 2",
          config.dims);
  require(std::isfinite(config.amount) && config.amount >= 0, "heat_diffusion",
          "amount must be finite and ≥ 0", config.amount);
  // The kernel, its logarithm and a field's complex spectra in both passes, about 8 reals per
  // cell; in double, so an n whose n² overflows Index is refused here too.
  const double cells = std::pow(static_cast<double>(config.n), config.dims);
  require_memory(8.0 * 8.0 * cells, "heat_diffusion: " + std::to_string(config.n) +
                                        " cells per axis in " + std::to_string(config.dims) +
                                        "-D (kernels and spectra, 64 B per cell)");
  const Index n = config.n, cols = config.dims == 2 ? n : 1;
  size_ = n * cols;
  log_kernel_.resize(size_);
  for (Index j = 0; j < cols; ++j) {
    for (Index i = 0; i < n; ++i) {
      const double ki = fftfreq(i, n), kj = cols == 1 ? 0.0 : fftfreq(j, n);
      log_kernel_(i + n * j) =
          4 * std::numbers::pi * std::numbers::pi * (ki * ki + kj * kj) * config.amount;
    }
  }
  kernel_ = (-log_kernel_).array().exp();
}

Matrix HeatDiffusion::diffuse(const Matrix& fields) const {
  const Index n = config_.n, cols = size_ / n;
  const Eigen::Map<const Matrix> kernel_grid(kernel_.data(), n, cols);
  Fft fft;
  Matrix out(size_, fields.cols());
  for (Index b = 0; b < fields.cols(); ++b) {
    throw_if_stop_requested("heat_diffusion");
    const Eigen::Map<const Matrix> field(fields.col(b).data(), n, cols);
    const ComplexMatrix spectrum =
        transform(fft, field.cast<Complex>(), false).cwiseProduct(kernel_grid.cast<Complex>());
    Eigen::Map<Matrix>(out.col(b).data(), n, cols) = transform(fft, spectrum, true).real();
  }
  return out;
}

Matrix HeatDiffusion::forward_batch(const Matrix& x, const Matrix& context) const {
  check_batch(x, context, "forward");
  return diffuse(x);
}

Matrix HeatDiffusion::vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const {
  check_vjp_batch(x, context, gy);
  return diffuse(gy);
}

Matrix HeatDiffusion::weighted_hessian(const Vector& x, const Vector& context,
                                       const Vector& /*w*/) const {
  check_batch(x, context, "weighted_hessian");
  return Matrix::Zero(size_, size_);
}

Vector HeatDiffusion::inverse_diffusion(const Vector& dy, double uncertainty_scale,
                                        double uncertainty_floor) const {
  if (dy.size() != size_) {
    throw Error(std::string("heat_diffusion.inverse_diffusion: dy has ") +
                std::to_string(dy.size()) + " values, expected " + std::to_string(size_));
  }
  require(std::isfinite(uncertainty_scale) && uncertainty_scale >= 0, "heat_diffusion",
          "uncertainty_scale must be finite and ≥ 0", uncertainty_scale);
  require(std::isfinite(uncertainty_floor) && uncertainty_floor >= 0, "heat_diffusion",
          "uncertainty_floor must be finite and ≥ 0", uncertainty_floor);

  const double noise = (dy.array().abs() * uncertainty_scale + uncertainty_floor).matrix().norm();
  const Index n = config_.n, cols = size_ / n;
  Fft fft;
  const Eigen::Map<const Matrix> field(dy.data(), n, cols);
  ComplexMatrix amp = transform(fft, field.cast<Complex>(), false);
  for (Index m = 0; m < size_; ++m) {
    const double a = std::abs(amp(m));
    const double signal = likelihood(a, static_cast<double>(n) * kernel_(m));
    const double total = signal + likelihood(a, noise);
    const double p = total > 0 ? signal / total : 0.0;
    const double action = (p <= 0.5 || p >= 0.68) ? 2 * (p - 0.5) : 0.0;
    amp(m) *= std::exp(std::min(log_kernel_(m) * action, kMaxLogGain));
  }
  Vector dx(size_);
  Eigen::Map<Matrix>(dx.data(), n, cols) = transform(fft, amp, true).real();
  return dx;
}

Vector HeatDiffusion::inverse(const Vector& y, const Vector& x0, const Vector& context) const {
  check_batch(x0, context, "inverse");
  if (y.size() != size_) {
    throw Error(std::string("heat_diffusion.inverse: y has ") + std::to_string(y.size()) +
                " values, expected " + std::to_string(size_));
  }
  return x0 + inverse_diffusion(y - forward(x0), 1e-6, 1e-8);
}

}  // namespace physgrad
