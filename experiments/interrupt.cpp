#include "interrupt.hpp"

#include <csignal>

namespace physgrad::experiments {

namespace {

std::atomic<bool> stop{false};
std::atomic<int> signal_number{0};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free,
              "the signal handler needs lock-free atomics");

extern "C" void on_signal(int number) {
  if (stop.load()) {
    std::signal(number, SIG_DFL);  // the second one: end now
    std::raise(number);
    return;
  }
  signal_number.store(number);
  stop.store(true);
}

}  // namespace

void install_interrupt_handlers() {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
}

const std::atomic<bool>& stop_flag() { return stop; }

int received_signal() { return signal_number.load(); }

}  // namespace physgrad::experiments
