// Deterministic random numbers for data generation: the same values on every platform for a
// seed (std::mt19937_64 bits mapped by hand; the standard distributions are not portable).
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

namespace physgrad::experiments {

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

}  // namespace physgrad::experiments
