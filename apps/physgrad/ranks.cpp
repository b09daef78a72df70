#include "ranks.hpp"

#include <cstdlib>
#include <iostream>

#ifdef PHYSGRAD_WITH_MPI
#include "physgrad/parallel/mpi_communicator.hpp"
#endif

namespace physgrad::cli {

namespace {

std::shared_ptr<Communicator>& current() {
  static std::shared_ptr<Communicator> communicator = std::make_shared<SerialCommunicator>();
  return communicator;
}

}  // namespace

Ranks::Ranks([[maybe_unused]] int* argc, [[maybe_unused]] char*** argv) {
#ifdef PHYSGRAD_WITH_MPI
  if (launched_by_mpi()) current() = mpi_world_communicator(argc, argv);
#else
  // Several copies of a build without MPI would each train alone and race for the run folder.
  if (launcher_size() > 1) {
    std::cerr << "physgrad: error: this physgrad was built without MPI (PHYSGRAD_WITH_MPI off or "
                 "no MPI found), so it cannot share a run among "
              << launcher_size() << " processes; run it without mpirun\n";
    std::exit(2);
  }
#endif
}

Ranks::~Ranks() {
  std::cout.flush();
  current() = std::make_shared<SerialCommunicator>();  // the last reference: MPI_Finalize
}

const std::shared_ptr<Communicator>& communicator() { return current(); }

bool is_writer() { return current()->rank() == 0; }

std::string rank_prefix() {
  const Communicator& c = *current();
  if (c.size() == 1) return {};
  return "rank " + std::to_string(c.rank()) + " of " + std::to_string(c.size()) + ": ";
}

int end_run(int exit_code) {
  if (current()->size() > 1) {
    std::cout.flush();
    std::cerr.flush();
    current()->abort(exit_code);
  }
  return exit_code;
}

}  // namespace physgrad::cli
