#include "physgrad/parallel/scalapack_eigensolver.hpp"

#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cstddef>
#include <string>
#include <vector>

#include "physgrad/error.hpp"

#ifdef PHYSGRAD_WITH_SCALAPACK
// BLACS (C interface) and ScaLAPACK (Fortran interface, hidden lengths of the character
// arguments last) as libscalapack-openmpi provides them.
extern "C" {
int Csys2blacs_handle(MPI_Comm comm);
void Cfree_blacs_system_handle(int handle);
void Cblacs_gridinit(int* context, const char* order, int rows, int cols);
void Cblacs_gridinfo(int context, int* rows, int* cols, int* row, int* col);
void Cblacs_gridexit(int context);
void descinit_(int* desc, const int* m, const int* n, const int* mb, const int* nb,
               const int* row_source, const int* col_source, const int* context, const int* lld,
               int* info);
void pdsyevd_(const char* jobz, const char* uplo, const int* n, double* a, const int* ia,
              const int* ja, const int* desca, double* w, double* z, const int* iz, const int* jz,
              const int* descz, double* work, const int* lwork, int* iwork, const int* liwork,
              int* info, std::size_t jobz_length, std::size_t uplo_length);
}
#endif

namespace physgrad {

#ifdef PHYSGRAD_WITH_SCALAPACK
namespace {

constexpr int kBlock = 64;

int as_int(Index value, const char* what) {
  if (value > INT_MAX) {
    throw Error(std::string("ScaLAPACK: ") + what + " " + std::to_string(value) +
                " exceeds its integer range");
  }
  return static_cast<int>(value);
}

class ScalapackEigensolver final : public DistributedEigensolver {
 public:
  ScalapackEigensolver() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    handle_ = Csys2blacs_handle(MPI_COMM_WORLD);
    context_ = handle_;
    Cblacs_gridinit(&context_, "Row", 1, size_);
    int rows = 0, cols = 0, row = 0, col = 0;
    Cblacs_gridinfo(context_, &rows, &cols, &row, &col);
    if (rows != 1 || cols != size_ || col != rank_) {
      throw Error("ScaLAPACK: the BLACS grid is not 1 × " + std::to_string(size_) +
                  " in rank order");
    }
  }
  ~ScalapackEigensolver() override {
    Cblacs_gridexit(context_);
    Cfree_blacs_system_handle(handle_);
  }
  ScalapackEigensolver(const ScalapackEigensolver&) = delete;
  ScalapackEigensolver& operator=(const ScalapackEigensolver&) = delete;

  std::string name() const override { return "scalapack pdsyevd"; }
  Index block() const override { return kBlock; }
  int rank() const override { return rank_; }
  int size() const override { return size_; }

  Vector decompose(Matrix& local, Index n) override {
    const auto columns = static_cast<Index>(block_cyclic_columns(n, kBlock, rank_, size_).size());
    if (local.rows() != n || local.cols() != columns) {
      throw Error("ScaLAPACK: rank " + std::to_string(rank_) + " holds " +
                  std::to_string(local.rows()) + "×" + std::to_string(local.cols()) +
                  " of an n = " + std::to_string(n) + " matrix, expected " + std::to_string(n) +
                  "×" + std::to_string(columns));
    }
    Vector lambda(n);
    if (n == 0) return lambda;
    const int order = as_int(n, "n");
    const int lld = std::max(1, order), zero = 0, one = 1;
    int desc[9];
    int status = 0;
    descinit_(desc, &order, &order, &kBlock, &kBlock, &zero, &zero, &context_, &lld, &status);
    if (status != 0) throw Error("ScaLAPACK: descinit failed (info = " + std::to_string(status) + ")");
    Matrix vectors(n, columns);
    // Workspace query, then the decomposition.
    double work_size = 0;
    int iwork_size = 0, query = -1;
    pdsyevd_("V", "L", &order, local.data(), &one, &one, desc, lambda.data(), vectors.data(), &one,
             &one, desc, &work_size, &query, &iwork_size, &query, &status, 1, 1);
    if (status != 0) {
      throw NumericalError("ScaLAPACK: pdsyevd workspace query failed (info = " +
                           std::to_string(status) + ")");
    }
    // The query (and the documented minimum) can answer less than the back-transformation
    // inside pdsyevd needs on small matrices, where PDORMTR then rejects LWORK: at least
    // max(b(b − 1)/2, (np + nq)·b) + b² beyond pdsyevd's own 4n (np = n rows, nq columns here).
    const double rows = static_cast<double>(n), cols = static_cast<double>(columns), b = kBlock;
    const double back_transformation =
        std::max(b * (b - 1) / 2, (rows + cols) * b) + b * b + 5 * rows;
    std::vector<double> work(static_cast<std::size_t>(std::max(work_size, back_transformation)) +
                             1);
    std::vector<int> iwork(static_cast<std::size_t>(std::max(iwork_size, 1)));
    const int lwork = as_int(static_cast<Index>(work.size()), "workspace");
    const int liwork = as_int(static_cast<Index>(iwork.size()), "workspace");
    pdsyevd_("V", "L", &order, local.data(), &one, &one, desc, lambda.data(), vectors.data(), &one,
             &one, desc, work.data(), &lwork, iwork.data(), &liwork, &status, 1, 1);
    if (status != 0) {
      throw NumericalError("ScaLAPACK: pdsyevd failed (info = " + std::to_string(status) + ")");
    }
    // A rank that holds no column of a small matrix does not receive the eigenvalues; rank 0's
    // go to all, so every rank keeps the same pairs.
    MPI_Bcast(lambda.data(), order, MPI_DOUBLE, 0, MPI_COMM_WORLD);
    local = std::move(vectors);
    return lambda;
  }

 private:
  int rank_ = 0;
  int size_ = 1;
  int handle_ = 0;
  int context_ = 0;
};

}  // namespace

std::unique_ptr<DistributedEigensolver> scalapack_eigensolver() {
  return std::make_unique<ScalapackEigensolver>();
}
#else
std::unique_ptr<DistributedEigensolver> scalapack_eigensolver() { return nullptr; }
#endif

}  // namespace physgrad
