#include "physgrad/stop.hpp"

#include <string>

namespace physgrad {

namespace {
std::atomic<bool> acknowledged{false};
std::atomic<int> deferrals{0};
static_assert(std::atomic<bool>::is_always_lock_free,
              "request_stop() must be safe in a signal handler");
}  // namespace

namespace detail {

std::atomic<bool> stop_request{false};

void stop_at(const char* where) {
  if (deferrals.load() > 0) return;
  acknowledge_stop();
  throw StopRequested(std::string(where) + ": stopped on request");
}

}  // namespace detail

void request_stop() noexcept { detail::stop_request.store(true); }

void clear_stop_request() noexcept {
  detail::stop_request.store(false);
  acknowledged.store(false);
}

const std::atomic<bool>& stop_request_flag() noexcept { return detail::stop_request; }

void acknowledge_stop() noexcept { acknowledged.store(true); }

bool stop_acknowledged() noexcept { return acknowledged.load(); }

DeferStopPolls::DeferStopPolls() noexcept { deferrals.fetch_add(1); }

DeferStopPolls::~DeferStopPolls() { deferrals.fetch_sub(1); }

}  // namespace physgrad
