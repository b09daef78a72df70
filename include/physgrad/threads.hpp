// Threads of the BLAS/LAPACK library behind the linear algebra (OpenBLAS when it is the active
// implementation). Multithreaded BLAS pays off only for large matrices and hurts on busy cores.
#pragma once

namespace physgrad {

// Sets the number of BLAS threads when the BLAS in use supports it (OpenBLAS); returns false,
// doing nothing, otherwise. Throws Error unless threads ≥ 1.
bool set_blas_threads(int threads);

// The BLAS library's current thread count, or 0 when it cannot tell.
int blas_threads();

}  // namespace physgrad
