// Stop requests — one process-wide flag that asks long computations to end early: request_stop()
// sets it (a signal handler may call it), the simulators' time loops poll it every time step.
#pragma once

#include <atomic>
#include <stdexcept>

namespace physgrad {

// Thrown by throw_if_stop_requested(): the computation was cut short on request and its result
// does not exist. Not an Error: nothing was wrong with its input.
class StopRequested : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace detail {
extern std::atomic<bool> stop_request;
// Throws StopRequested("WHERE: stopped on request") unless polls are deferred.
void stop_at(const char* where);
}  // namespace detail

// Sets the flag. Async-signal-safe (a lock-free atomic store): a SIGINT handler may call it.
void request_stop() noexcept;
// Clears the flag, so that a later computation runs to its end again.
void clear_stop_request() noexcept;
// Whether a stop was requested (and not cleared since).
inline bool stop_requested() noexcept {
  return detail::stop_request.load(std::memory_order_relaxed);
}
// The flag itself, for a loop that polls a pointer (TrainerOptions::stop).
const std::atomic<bool>& stop_request_flag() noexcept;

// The poll of a long computation: one relaxed atomic load while no stop is requested. After a
// request it marks the stop as acknowledged and throws StopRequested("WHERE: stopped on
// request"), unless a DeferStopPolls is alive.
inline void throw_if_stop_requested(const char* where) {
  if (stop_requested()) [[unlikely]] detail::stop_at(where);
}

// Whether a computation saw the request and is ending in order: set before every
// StopRequested is thrown, and by acknowledge_stop() at a stop point of one's own. A watchdog
// that ends a process whose request goes unanswered (the CLI's) stands down once it is set.
void acknowledge_stop() noexcept;
bool stop_acknowledged() noexcept;

// While one exists (in any thread), throw_if_stop_requested() does not throw: for a caller that
// stops at points of its own, such as training shared by several processes, where all of them
// must stop at the same iteration and none may leave a collective operation half done.
class DeferStopPolls {
 public:
  DeferStopPolls() noexcept;
  ~DeferStopPolls();
  DeferStopPolls(const DeferStopPolls&) = delete;
  DeferStopPolls& operator=(const DeferStopPolls&) = delete;
};

}  // namespace physgrad
