// The run layer's fault injection points, private to src/run (not installed): the tests end a
// run at a named step to check what the folder holds after a kill, a failure or a stop there.
#pragma once

namespace physgrad::run {

// Fault injection for tests: with PHYSGRAD_FAULT=ACTION@NAME:K the K-th pass through the point
// NAME ("claimed": the folder is claimed, and a new run's config.json written; "checkpoint": a
// checkpoint was written; "commit": a result was moved into place) kills the process (ACTION
// "kill", SIGKILL), throws an Error ("fail"), or stops it ("stop", SIGSTOP: it waits, exactly
// there, until it gets SIGCONT; a test that sees it stopped with waitpid(WUNTRACED) changes the
// folders meanwhile, at a known step instead of after a guessed sleep). Does nothing without the
// variable.
void fault_point(const char* name);

}  // namespace physgrad::run
