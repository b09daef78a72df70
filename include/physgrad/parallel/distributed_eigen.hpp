// DistributedEigensolver — the truncated power x = Σ_{σᵢ > τ·σ_max} uᵢ σᵢ^{−1−κ} (uᵢᵀ g) of a
// symmetric n × n matrix U diag(σᵢ²) Uᵀ whose columns are spread over the ranks (1 × K
// block-cyclic: column c lives on rank ⌊c / b⌋ mod K), without forming U.
#pragma once

#include <string>
#include <vector>

#include "physgrad/spectral_cut.hpp"
#include "physgrad/types.hpp"

namespace physgrad {

// The columns of an n × n matrix that rank `rank` of `size` holds in the 1 × size block-cyclic
// layout with blocks of `block` columns, ascending. Throws Error on block < 1 or a bad rank.
std::vector<Index> block_cyclic_columns(Index n, Index block, int rank, int size);

// What a truncated power over a distributed matrix did.
struct DistributedPowerInfo {
  Index kept = 0;         // σᵢ > cut
  double sigma_max = 0;   // √λ_max
  double sigma_min_kept = 0;
};

// Implemented over MPI with ScaLAPACK (library physgrad_mpi, when CMake finds ScaLAPACK):
// the matrix is reduced to a tridiagonal T = Qᵀ A Q together (pdsytrd), every rank takes the
// eigenvalues of T (dsterf) and the eigenvectors S of its share of the kept ones (dstemr), and
// x = Q S σ^{−1−κ} Sᵀ Qᵀ g (pdormtr, one sum of n doubles). Neither U nor any n × n matrix
// beyond each rank's own columns is held. Every rank calls truncated_power() with the same
// n, g and cut (a collective); the cut keeps and weighs the spectrum as every other path does
// (cut_squared in spectral_cut.hpp: σ = √λ > τ·σ_max, weight σ^{−1−κ}).
class DistributedEigensolver {
 public:
  virtual ~DistributedEigensolver() = default;
  virtual std::string name() const = 0;
  virtual Index block() const = 0;  // b of the layout
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // `local` holds this rank's columns block_cyclic_columns(n, block(), rank(), size()) of the
  // symmetric matrix (n × count, full columns; consumed). Returns x, the same bits on every
  // rank. Throws NumericalError when a ScaLAPACK or LAPACK routine fails.
  virtual Vector truncated_power(Matrix local, Index n, const Vector& g, const SpectralCut& cut,
                                 DistributedPowerInfo* info) = 0;
};

// solver.truncated_power() after checking the sizes (Error) and that `local` and `g` are finite
// (NumericalError).
Vector distributed_truncated_power(DistributedEigensolver& solver, Matrix local, Index n,
                                   const Vector& g, const SpectralCut& cut,
                                   DistributedPowerInfo* info = nullptr);

// From how many rows (B·m) a data-parallel Gram path hands its truncated power to the ranks'
// DistributedEigensolver instead of repeating the eigendecomposition on every rank; 0 = never.
// Process-wide; the default is kDefaultDistributedGramRows (docs/distributed.md: there two ranks
// on one machine took 0.92× the time of one rank's tridiagonal eigensolver and 0.44× its memory;
// at 4096 they took 1.10× the time; the MPI equality tests' configurations stay below it). Throws
// Error on a negative value.
inline constexpr Index kDefaultDistributedGramRows = 8192;
void set_distributed_gram_rows(Index rows);
Index distributed_gram_rows();

}  // namespace physgrad
