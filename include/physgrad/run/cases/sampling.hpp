// Deterministic random numbers for data generation: the same values on every platform for a
// seed (std::mt19937_64 bits mapped by hand; the standard distributions are not portable).
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

#include "physgrad/types.hpp"

namespace physgrad::run {

class Sampler {
 public:
  explicit Sampler(std::uint64_t seed) : engine_(seed) {}
  // U[0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // N(0, 1) by the Box-Muller transform.
  double normal() {
    const double u = 1.0 - uniform();  // (0, 1]
    return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * M_PI * uniform());
  }

 private:
  std::mt19937_64 engine_;
};

// `count` smooth periodic random fields on an n × n grid of unit cells (one per column, cell
// (i, j) at row i + n·j), as phiflow's Noise(scale, smoothness) samples them on a grid: complex
// Fourier coefficients with real and imaginary parts N(0, 1), weighted by (1/|k|²)^smoothness
// with k = scale·fftfreq(n) per axis (physical wavenumbers of unit cells) and set to 0 where
// |k|² ≤ 0.1 (the mean); the real part of their inverse DFT; then each field divided by its
// standard deviation and its mean subtracted. O(n³) per field (two passes of 1-D sums).
Matrix periodic_noise(Index count, Index n, Sampler& sampler, double scale = 10,
                      double smoothness = 1);

}  // namespace physgrad::run
