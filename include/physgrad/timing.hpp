// Timing — the seconds since a moment on the steady clock, the one clock of every duration the
// library reports (step timings, training time, budgets).
#pragma once

#include <chrono>

namespace physgrad {

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace physgrad
