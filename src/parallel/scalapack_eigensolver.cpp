#include "physgrad/parallel/scalapack_eigensolver.hpp"

#include <lapacke.h>
#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cmath>
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
void pdsytrd_(const char* uplo, const int* n, double* a, const int* ia, const int* ja,
              const int* desca, double* d, double* e, double* tau, double* work, const int* lwork,
              int* info, std::size_t uplo_length);
void pdormtr_(const char* side, const char* uplo, const char* trans, const int* m, const int* n,
              const double* a, const int* ia, const int* ja, const int* desca, const double* tau,
              double* c, const int* ic, const int* jc, const int* descc, double* work,
              const int* lwork, int* info, std::size_t side_length, std::size_t uplo_length,
              std::size_t trans_length);
}
#endif

namespace physgrad {

#ifdef PHYSGRAD_WITH_SCALAPACK
namespace {

constexpr int kBlock = 64;
// Eigenvectors of T computed at a time (n × kChunk doubles each).
constexpr Index kChunk = 512;

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

  std::string name() const override { return "scalapack pdsytrd + dstemr"; }
  Index block() const override { return kBlock; }
  int rank() const override { return rank_; }
  int size() const override { return size_; }

  Vector truncated_power(Matrix local, Index n, const Vector& g, const SpectralCut& cut,
                         DistributedPowerInfo* info) override {
    Vector x = Vector::Zero(n);
    *info = {};
    if (n == 0) return x;
    const std::vector<Index> columns = block_cyclic_columns(n, kBlock, rank_, size_);
    const int order = as_int(n, "n");
    const int one = 1;
    int a_desc[9];
    describe(a_desc, order, order);

    // 1. T = Qᵀ A Q; A keeps the Householder vectors of Q, tau their factors (per local column).
    const auto owned = static_cast<std::size_t>(std::max<Index>(1, local.cols()));
    std::vector<double> d_local(owned), e_local(owned), tau(owned);
    int status = 0;
    const auto reduce = [&](double* work, int lwork) {
      pdsytrd_("L", &order, local.data(), &one, &one, a_desc, d_local.data(), e_local.data(),
               tau.data(), work, &lwork, &status, 1);
      if (status != 0) {
        throw NumericalError("ScaLAPACK: pdsytrd failed (info = " + std::to_string(status) + ")");
      }
    };
    with_workspace(reduce);

    // 2. T's diagonal and subdiagonal on every rank (each entry comes from one rank, so the sum
    //    is exact), its eigenvalues and the cut.
    Vector d = Vector::Zero(n), e = Vector::Zero(n);
    for (std::size_t s = 0; s < columns.size(); ++s) {
      d(columns[s]) = d_local[s];
      if (columns[s] + 1 < n) e(columns[s]) = e_local[s];
    }
    sum_everywhere(d);
    sum_everywhere(e);
    Vector lambda = d, scratch = e;
    check_lapack(LAPACKE_dsterf(order, lambda.data(), scratch.data()), "dsterf");  // ascending
    const CutSpectrum kept = cut_squared(cut, lambda);  // the kept λ are the last ones
    info->sigma_max = kept.sigma_max;
    info->kept = kept.kept;
    info->sigma_min_kept = kept.sigma_min_kept;
    if (info->kept == 0) return x;
    const double lambda_max = std::max(lambda(n - 1), 0.0);

    // 3. h = Qᵀ g (on rank 0, which holds the one column of an n × 1 matrix), then to all.
    Vector h = g;
    apply_q(local, a_desc, tau, h, "T");

    // 4. Each rank's share of the kept eigenpairs of T, in chunks: y = Σ S σ^{−1−κ} Sᵀ h.
    const Index first = n - info->kept;
    const Index begin = first + info->kept * rank_ / size_;
    const Index end = first + info->kept * (rank_ + 1) / size_;
    Vector y = Vector::Zero(n);
    for (Index lo = begin; lo < end; lo += kChunk) {
      const Index hi = std::min(end, lo + kChunk);
      Vector dd = d, ee = e, w(n);  // dstemr writes up to n eigenvalues
      Matrix s(n, hi - lo);
      std::vector<lapack_int> support(static_cast<std::size_t>(2 * (hi - lo)));
      lapack_int found = 0;
      lapack_logical relative = 1;
      check_lapack(LAPACKE_dstemr(LAPACK_COL_MAJOR, 'V', 'I', order, dd.data(), ee.data(), 0.0,
                                  0.0, as_int(lo + 1, "index"), as_int(hi, "index"), &found,
                                  w.data(), s.data(), order, as_int(hi - lo, "count"),
                                  support.data(), &relative),
                   "dstemr");
      if (found != hi - lo) {
        throw NumericalError("LAPACK: dstemr found " + std::to_string(found) + " of " +
                             std::to_string(hi - lo) + " eigenpairs");
      }
      Vector weights = s.transpose() * h;
      for (Index i = 0; i < weights.size(); ++i) {
        weights(i) *= cut.lambda_weight(w(i), lambda_max);
      }
      y.noalias() += s * weights;
    }
    sum_everywhere(y);

    // 5. x = Q y.
    apply_q(local, a_desc, tau, y, "N");
    return y;
  }

 private:
  // The descriptor of a rows × cols matrix in the 1 × K grid, blocks of kBlock × kBlock.
  void describe(int* desc, int rows, int cols) const {
    const int zero = 0, block = kBlock, lld = std::max(1, rows);
    int status = 0;
    descinit_(desc, &rows, &cols, &block, &block, &zero, &zero, &context_, &lld, &status);
    if (status != 0) {
      throw Error("ScaLAPACK: descinit failed (info = " + std::to_string(status) + ")");
    }
  }

  // Calls run(work, lwork) once as a workspace query (lwork = −1), then with that workspace.
  template <typename Run>
  static void with_workspace(const Run& run) {
    double size = 0;
    run(&size, -1);
    std::vector<double> work(static_cast<std::size_t>(std::max(size, 1.0)) + 1);
    run(work.data(), as_int(static_cast<Index>(work.size()), "workspace"));
  }

  // v ← Q v ("N") or Qᵀ v ("T") with Q from pdsytrd held in `a` and `tau`: v is the one column of
  // an n × 1 matrix, which lives on rank 0; the result goes to every rank.
  void apply_q(const Matrix& a, const int* a_desc, const std::vector<double>& tau, Vector& v,
               const char* trans) const {
    const int order = as_int(v.size(), "n"), one = 1;
    int c_desc[9];
    describe(c_desc, order, 1);
    int status = 0;
    const auto run = [&](double* work, int lwork) {
      pdormtr_("L", "L", trans, &order, &one, a.data(), &one, &one, a_desc, tau.data(), v.data(),
               &one, &one, c_desc, work, &lwork, &status, 1, 1, 1);
      if (status != 0) {
        throw NumericalError("ScaLAPACK: pdormtr failed (info = " + std::to_string(status) + ")");
      }
    };
    with_workspace(run);
    MPI_Bcast(v.data(), order, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  }

  // v ← the sum of every rank's v, the same bits everywhere (a reduce to rank 0, then a broadcast).
  void sum_everywhere(Vector& v) const {
    const int count = as_int(v.size(), "vector");
    Vector total(v.size());
    MPI_Reduce(v.data(), total.data(), count, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    if (rank_ == 0) v = total;
    MPI_Bcast(v.data(), count, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  }

  static void check_lapack(lapack_int status, const char* routine) {
    if (status != 0) {
      throw NumericalError(std::string("LAPACK: ") + routine + " failed (info = " +
                           std::to_string(status) + ")");
    }
  }

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
