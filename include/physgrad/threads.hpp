// Threads of the BLAS/LAPACK library behind the linear algebra (OpenBLAS when it is the active
// implementation), and of the physics VJPs of the stacked Jacobian. Both pay off only on idle
// cores; on busy ones they cost more than they save.
#pragma once

#include <string>

namespace physgrad {

// Sets the number of BLAS threads when the BLAS in use supports it (OpenBLAS); returns false,
// doing nothing, otherwise. Throws Error unless threads ≥ 1.
bool set_blas_threads(int threads);

// The BLAS library's current thread count, or 0 when it cannot tell.
int blas_threads();

// The kernel set OpenBLAS chose for this CPU (openblas_get_corename(), e.g. "Haswell"), or ""
// when the BLAS is not OpenBLAS.
std::string blas_core();

// A one-line note when OpenBLAS runs generic kernels on an x86-64 CPU with AVX2 and FMA, else "".
// OpenBLAS picks its kernels from the CPU models it knows; on a newer one (Debian 12's 0.3.21
// on a Xeon with AVX-512 FP16) it falls back to "Prescott" (SSE3): dsyrk measured 3.9–6.6× and
// dsyevd 1.7× slower than with the kernels the CPU can run (docs/performance.md). The note names
// the OPENBLAS_CORETYPE value to set (read when OpenBLAS loads, so before the program starts).
std::string blas_core_note();

// Threads that compute the m batched physics VJPs of a StackedJacobian (one per output k, each
// into its own matrix, so the result does not depend on the count); 1, the default, runs them
// in the calling thread. With more, the simulator's vjp_batch is called concurrently on the
// same const object: every built-in simulator allows that. Process-wide; throws Error unless
// threads ≥ 1.
void set_jacobian_threads(int threads);
int jacobian_threads();

}  // namespace physgrad
