// Interrupts — SIGINT and SIGTERM as a request to stop. The first signal sets a flag that the
// experiments poll: a learning run saves a checkpoint and stops (`physgrad resume` continues
// it), any other run stops and writes nothing. A second signal ends the process at once.
#pragma once

#include <atomic>
#include <stdexcept>

namespace physgrad::experiments {

// Thrown by an experiment that stopped on request.
class Interrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

void install_interrupt_handlers();
const std::atomic<bool>& stop_flag();
// The signal that set the flag (SIGINT or SIGTERM), 0 while none has arrived.
int received_signal();

}  // namespace physgrad::experiments
