// The processes of one CLI run: under mpirun (in a build with MPI) the ranks of MPI_COMM_WORLD,
// otherwise this process alone. Rank 0 prints and writes the run folder; the others only compute.
#pragma once

#include <memory>
#include <string>

#include "physgrad/parallel/communicator.hpp"
#include "physgrad/run/life/experiment.hpp"

namespace physgrad::cli {

// Made once at the start of main(): initializes MPI only when the build has it and a launcher
// started this process, with the time limit of rank_timeout_seconds() (a bad
// PHYSGRAD_RANK_TIMEOUT ends the process with exit code 2 before MPI starts); finalizes it when
// destroyed.
class Ranks {
 public:
  Ranks(int* argc, char*** argv);
  ~Ranks();
  Ranks(const Ranks&) = delete;
  Ranks& operator=(const Ranks&) = delete;
};

// The communicator of this run (serial before Ranks is made or without MPI).
const std::shared_ptr<Communicator>& communicator();
// True on the rank that prints and writes (rank 0).
bool is_writer();
// "rank R of K: " in a run of several ranks, empty otherwise.
std::string rank_prefix();
// Prints "physgrad: error: rank R of K: MESSAGE" (without the rank alone) as one line in one
// write, so that the lines of several ranks do not run into each other.
void print_error(const std::string& message);
// The ranks' time limit as the ranks compare it ("300").
std::string rank_timeout_text();
// What this process was started to do, for the ranks to compare: for a run of `experiment`
// its name and every resolved setting in `settings`, else the whole command line after the
// program; then the rank time limit.
RankCommand rank_command(int argc, char** argv, const run::Experiment* experiment,
                         const run::Settings* settings);
// Before anything is done: checks that every rank was started with the same `command`. Returns
// 0, or, after printing the error line, 2 — every rank sees the same difference and ends by
// itself — or end_run(2) when a rank did not take part within the time limit.
int require_same_command(const RankCommand& command);
// After an error on this rank: in a run of several ranks ends all of them with `exit_code`
// (MPI_Abort), so none waits forever; otherwise returns `exit_code`. A rank other than 0 that
// lost contact with the others first leaves rank 0 a few seconds to save its checkpoint and end
// the job itself.
int end_run(int exit_code);
// The end of main(): in a run of several ranks, waits (at most the time limit) until every rank
// has come to its end, and returns `exit_code`; when that wait fails, or this rank lost contact
// before, ends the job by end_run() (exit code 2 for a failed wait).
int finish(int exit_code);

}  // namespace physgrad::cli
