#include "physgrad/run/life/interrupt.hpp"

#include <semaphore.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <thread>

namespace physgrad::run {

namespace {

std::atomic<int> signal_number{0};
std::atomic<double> grace{10.0};
sem_t requested;  // posted by the first signal, for the watcher thread
static_assert(std::atomic<int>::is_always_lock_free,
              "the signal handler needs lock-free atomics");

// Ends the process by `number` with its default action (termination).
void end_by(int number) {
  std::signal(number, SIG_DFL);
  ::kill(::getpid(), number);
}

extern "C" void on_signal(int number) {
  if (stop_requested()) {
    end_by(number);  // the second one: end now
    return;
  }
  signal_number.store(number);
  request_stop();
  ::sem_post(&requested);  // async-signal-safe
}

// Waits for the first signal, then for a stop point within the grace period; ends the process
// when none comes.
void watch() {
  while (::sem_wait(&requested) != 0 && errno == EINTR) {
  }
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration<double>(grace.load());
  while (!stop_acknowledged() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (stop_acknowledged()) return;
  const int number = signal_number.load();
  std::fprintf(stderr,
               "\nphysgrad: %s: no stop point reached within %g s (blocked in a step that does "
               "not poll for stops); ended without saving this state: the run folder keeps its "
               "last checkpoint, or only its settings, and physgrad resume goes on from there\n",
               number == SIGINT ? "SIGINT" : "SIGTERM", grace.load());
  std::fflush(stderr);
  end_by(number);
}

}  // namespace

double stop_grace_seconds() {
  if (const char* text = std::getenv("PHYSGRAD_STOP_GRACE")) {
    char* end = nullptr;
    const double seconds = std::strtod(text, &end);
    if (end != text && *end == '\0' && seconds > 0 && seconds < 1e6) return seconds;
  }
  return 10.0;
}

void install_interrupt_handlers(double grace_seconds) {
  grace.store(grace_seconds);
  static std::once_flag once;
  std::call_once(once, [] {
    ::sem_init(&requested, 0, 0);
    std::thread(watch).detach();
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
  });
}

const std::atomic<bool>& stop_flag() { return stop_request_flag(); }

int received_signal() { return signal_number.load(); }

void stop_point_reached() { acknowledge_stop(); }

}  // namespace physgrad::run
