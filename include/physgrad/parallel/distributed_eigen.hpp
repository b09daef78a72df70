// DistributedEigensolver — the eigendecomposition of a symmetric n × n matrix whose columns are
// spread over the ranks (1 × K block-cyclic: column c lives on rank ⌊c / b⌋ mod K), and the
// truncated power it serves: x = Σ_{σᵢ > τ·σ_max} uᵢ σᵢ^{−1−κ} (uᵢᵀ g), σᵢ² the eigenvalues.
#pragma once

#include <string>
#include <vector>

#include "physgrad/types.hpp"

namespace physgrad {

// The columns of an n × n matrix that rank `rank` of `size` holds in the 1 × size block-cyclic
// layout with blocks of `block` columns, ascending. Throws Error on block < 1 or a bad rank.
std::vector<Index> block_cyclic_columns(Index n, Index block, int rank, int size);

// Implemented over MPI by ScaLAPACK (pdsyevd; library physgrad_mpi, when CMake finds ScaLAPACK).
// Every rank calls decompose() with the same n (a collective).
class DistributedEigensolver {
 public:
  virtual ~DistributedEigensolver() = default;
  virtual std::string name() const = 0;
  virtual Index block() const = 0;  // b of the layout
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // `local` holds this rank's columns block_cyclic_columns(n, block(), rank(), size()) of the
  // symmetric matrix (n × count; the lower triangle is read). Returns all n eigenvalues,
  // ascending, the same on every rank, and overwrites `local` with the eigenvectors of the same
  // indices (local column s: the eigenvector of eigenvalue columns[s]). Throws NumericalError
  // when the solver fails.
  virtual Vector decompose(Matrix& local, Index n) = 0;
};

// What a truncated power over a distributed matrix did.
struct DistributedPowerInfo {
  Index kept = 0;         // σᵢ > cut
  double sigma_max = 0;   // √λ_max
  double sigma_min_kept = 0;
};

// This rank's part of Σ_{σᵢ > rcond·σ_max} uᵢ σᵢ^{−1−κ} (uᵢᵀ g) for the symmetric matrix
// U diag(σᵢ²) Uᵀ held as in DistributedEigensolver::decompose (`local` is consumed); the sum of
// the parts over the ranks is the result. Throws NumericalError on non-finite entries.
Vector distributed_power_part(DistributedEigensolver& solver, Matrix local, Index n,
                              const Vector& g, double kappa, double rcond,
                              DistributedPowerInfo* info = nullptr);

// From how many rows (B·m) a data-parallel Gram path hands its eigendecomposition to the
// ranks' DistributedEigensolver instead of repeating it on every rank; 0 = never. Process-wide;
// the default is kDefaultDistributedGramRows (docs/distributed.md: below it two ranks on one
// machine were slower than one). Throws Error on a negative value.
inline constexpr Index kDefaultDistributedGramRows = 2048;
void set_distributed_gram_rows(Index rows);
Index distributed_gram_rows();

}  // namespace physgrad
