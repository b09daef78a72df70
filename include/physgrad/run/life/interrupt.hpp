// Interrupts — SIGINT and SIGTERM as a request to stop. The first signal sets the library's stop
// flag (physgrad/stop.hpp), which the experiments and the simulators' time loops poll: a
// learning run saves a checkpoint and stops (`physgrad resume` continues it), any other run
// stops and writes nothing. A process that reaches no stop point within the grace period after
// it (blocked in a read, an allocation or a computation that never polls), or that gets a second
// signal, ends at once, killed by that signal (exit status 128 + its number).
#pragma once

#include <atomic>

#include "physgrad/stop.hpp"

namespace physgrad::run {

// Thrown by an experiment that stopped on request, and by a simulator of the library that did.
using Interrupted = StopRequested;

// Seconds a stop request waits for a stop point: PHYSGRAD_STOP_GRACE if set to a number > 0,
// else 10.
double stop_grace_seconds();
// Installs the handlers (once; a later call only changes the grace period).
void install_interrupt_handlers(double grace_seconds = stop_grace_seconds());
// The library's stop flag (stop_request_flag()).
const std::atomic<bool>& stop_flag();
// The signal that set the flag (SIGINT or SIGTERM), 0 while none has arrived.
int received_signal();
// Called where a run has seen the stop request and ends in order (saving its checkpoint first):
// the grace period no longer applies (acknowledge_stop(), as every StopRequested thrown does).
void stop_point_reached();

}  // namespace physgrad::run
