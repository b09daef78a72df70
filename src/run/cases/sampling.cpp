#include "physgrad/run/cases/sampling.hpp"

#include <complex>
#include <vector>

#include "physgrad/error.hpp"

namespace physgrad::run {

Matrix periodic_noise(Index count, Index n, Sampler& sampler, double scale, double smoothness) {
  if (count < 0 || n < 1) {
    throw Error("periodic_noise: needs a grid size ≥ 1 and a count ≥ 0, got " +
                std::to_string(n) + " and " + std::to_string(count));
  }
  using Complex = std::complex<double>;
  // fftfreq(n): 0, 1, …, ⌈n/2⌉ − 1, then −⌊n/2⌋, …, −1, over n.
  std::vector<double> frequency(static_cast<std::size_t>(n));
  for (Index p = 0; p < n; ++p) {
    frequency[static_cast<std::size_t>(p)] =
        static_cast<double>(p < (n + 1) / 2 ? p : p - n) / static_cast<double>(n);
  }
  // The weight of mode (p, q) and e^{2πi·m/n}.
  Matrix weight(n, n);
  for (Index q = 0; q < n; ++q) {
    for (Index p = 0; p < n; ++p) {
      const double kx = scale * frequency[static_cast<std::size_t>(p)];
      const double ky = scale * frequency[static_cast<std::size_t>(q)];
      const double k2 = kx * kx + ky * ky;
      weight(p, q) = k2 > 0.1 ? std::pow(1 / k2, smoothness) : 0.0;
    }
  }
  std::vector<Complex> root(static_cast<std::size_t>(n));
  for (Index m = 0; m < n; ++m) {
    root[static_cast<std::size_t>(m)] =
        std::polar(1.0, 2 * M_PI * static_cast<double>(m) / static_cast<double>(n));
  }
  const auto e = [&](Index a, Index b) { return root[static_cast<std::size_t>((a * b) % n)]; };

  Matrix fields(n * n, count);
  Eigen::Matrix<Complex, Eigen::Dynamic, Eigen::Dynamic> c(n, n), half(n, n);
  for (Index s = 0; s < count; ++s) {
    for (Index q = 0; q < n; ++q) {
      for (Index p = 0; p < n; ++p) {
        const double re = sampler.normal();
        const double im = sampler.normal();
        c(p, q) = Complex(re, im) * weight(p, q);
      }
    }
    // half(p, j) = Σ_q c(p, q) e^{2πi·qj/n}; then field(i, j) = Re Σ_p half(p, j) e^{2πi·pi/n}.
    for (Index j = 0; j < n; ++j) {
      for (Index p = 0; p < n; ++p) {
        Complex sum = 0;
        for (Index q = 0; q < n; ++q) sum += c(p, q) * e(q, j);
        half(p, j) = sum;
      }
    }
    auto field = fields.col(s);
    for (Index j = 0; j < n; ++j) {
      for (Index i = 0; i < n; ++i) {
        Complex sum = 0;
        for (Index p = 0; p < n; ++p) sum += half(p, j) * e(p, i);
        field(i + n * j) = sum.real();
      }
    }
    const double mean = field.mean();
    const double deviation = std::sqrt((field.array() - mean).square().mean());
    if (deviation > 0) field /= deviation;
    field.array() -= field.mean();
  }
  return fields;
}

}  // namespace physgrad::run
