// phiflow's Noise as poisson samples it (run/sampling.hpp): the direct 2-D formula, zero mean and
// unit standard deviation per field, the weights (1/|k|²)^smoothness, the mean mode dropped.
#include <gtest/gtest.h>

#include <complex>

#include "physgrad/error.hpp"
#include "physgrad/run/cases/sampling.hpp"

namespace physgrad::run {
namespace {

// fftfreq(n)[p] = p/n for p < ⌈n/2⌉, (p − n)/n after.
double frequency(Index p, Index n) {
  return static_cast<double>(p < (n + 1) / 2 ? p : p - n) / static_cast<double>(n);
}

// The field from the same random numbers by the 2-D sum written out: Re Σ_pq c_pq w_pq
// e^{2πi(p·i + q·j)/n}, normalised.
Vector direct_field(Index n, Sampler& sampler, double scale, double smoothness) {
  std::vector<std::complex<double>> c(static_cast<std::size_t>(n * n));
  for (Index q = 0; q < n; ++q) {
    for (Index p = 0; p < n; ++p) {
      const double re = sampler.normal();
      const double im = sampler.normal();
      const double kx = scale * frequency(p, n), ky = scale * frequency(q, n);
      const double k2 = kx * kx + ky * ky;
      c[static_cast<std::size_t>(p + n * q)] =
          std::complex<double>(re, im) * (k2 > 0.1 ? std::pow(1 / k2, smoothness) : 0.0);
    }
  }
  Vector field(n * n);
  for (Index j = 0; j < n; ++j) {
    for (Index i = 0; i < n; ++i) {
      std::complex<double> sum = 0;
      for (Index q = 0; q < n; ++q) {
        for (Index p = 0; p < n; ++p) {
          sum += c[static_cast<std::size_t>(p + n * q)] *
                 std::polar(1.0, 2 * M_PI * static_cast<double>(p * i + q * j) /
                                     static_cast<double>(n));
        }
      }
      field(i + n * j) = sum.real();
    }
  }
  field /= std::sqrt((field.array() - field.mean()).square().mean());
  field.array() -= field.mean();
  return field;
}

TEST(PeriodicNoise, MatchesTheDirectFormulaAndIsNormalisedPerField) {
  for (const auto& [n, scale, smoothness] :
       {std::tuple{8, 10.0, 1.0}, std::tuple{5, 10.0, 1.0}, std::tuple{6, 3.0, 2.0}}) {
    Sampler a(42), b(42);
    const Matrix fields = periodic_noise(3, n, a, scale, smoothness);
    ASSERT_EQ(fields.rows(), n * n);
    for (Index s = 0; s < 3; ++s) {
      const Vector direct = direct_field(n, b, scale, smoothness);
      EXPECT_LT((fields.col(s) - direct).cwiseAbs().maxCoeff(), 1e-12) << n << " " << s;
      EXPECT_NEAR(fields.col(s).mean(), 0, 1e-14);
      EXPECT_NEAR(fields.col(s).squaredNorm() / static_cast<double>(n * n), 1, 1e-12);
    }
  }
}

// Smoothness 1 weights each mode by 1/|k|²: the field's own DFT has no mean mode, and a low mode
// carries far more power than the highest, over many fields.
TEST(PeriodicNoise, PowerFallsWithTheWavenumber) {
  Sampler sampler(7);
  const Index n = 8;
  const Matrix fields = periodic_noise(400, n, sampler);
  double low = 0, high = 0;
  for (Index s = 0; s < fields.cols(); ++s) {
    std::complex<double> mode_low = 0, mode_high = 0, mode_zero = 0;
    for (Index j = 0; j < n; ++j) {
      for (Index i = 0; i < n; ++i) {
        const double v = fields(i + n * j, s);
        mode_zero += v;
        mode_low += v * std::polar(1.0, -2 * M_PI * static_cast<double>(i) / n);
        mode_high += v * std::polar(1.0, -2 * M_PI * static_cast<double>(4 * i + 4 * j) / n);
      }
    }
    EXPECT_LT(std::abs(mode_zero), 1e-10);
    low += std::norm(mode_low);
    high += std::norm(mode_high);
  }
  // |k|² of mode (1, 0) is 100/64, of (4, 4) 100/2: power ratio (32)² in expectation.
  EXPECT_GT(low / high, 300);
  EXPECT_THROW(periodic_noise(1, 0, sampler), Error);
}

}  // namespace
}  // namespace physgrad::run
