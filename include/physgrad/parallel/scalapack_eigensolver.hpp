// ScaLAPACK's DistributedEigensolver over MPI_COMM_WORLD (library physgrad_mpi, built when CMake
// finds ScaLAPACK): a 1 × K BLACS process grid, blocks of 64 columns, pdsytrd + dstemr + pdormtr.
#pragma once

#include <memory>

#include "physgrad/parallel/distributed_eigen.hpp"

namespace physgrad {

// Needs MPI initialized; the solver must be destroyed before MPI is finalized. Null when the
// build has no ScaLAPACK.
std::unique_ptr<DistributedEigensolver> scalapack_eigensolver();

}  // namespace physgrad
