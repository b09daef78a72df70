// Timing — the seconds since a moment on the steady clock, the one clock of every duration the
// library reports (step timings, training time, budgets); and the process's CPU time, which the
// cost probes compare (TrainerOptions::cost_reference), since waiting for a core does not count
// in it.
#pragma once

#include <chrono>
#include <ctime>

namespace physgrad {

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// CPU seconds this process has used so far, in all its threads (CLOCK_PROCESS_CPUTIME_ID).
inline double process_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

}  // namespace physgrad
