// Run under mpiexec by the Mpi.* tests: the ranks' DistributedEigensolver (ScaLAPACK) applied as
// a truncated power, Σ_{σᵢ > τσ_max} uᵢ σᵢ^{−1−κ} uᵢᵀ g, against one process's dsyevd path
// (power_pinv_apply_gram with Jᵀ = identity) on matrices of known spectrum, including sizes with
// ranks that hold no column and one (n = 1100) whose eigenvectors two ranks compute in two chunks
// each. Prints one line per case; exit code 0 when all agree to 1e-10, 1 when one does not, 3
// when the build has no distributed solver.
#include <cstdio>
#include <random>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/parallel/communicator.hpp"
#include "physgrad/parallel/distributed_eigen.hpp"
#include "physgrad/parallel/mpi_communicator.hpp"

namespace {

using physgrad::Index;
using physgrad::Matrix;
using physgrad::Vector;

// Q diag(λ) Qᵀ with λ from 1 down to `smallest` (log-spaced) and `zeros` zero eigenvalues; the
// same bits on every rank (fixed seed).
Matrix known_spectrum(Index n, double smallest, Index zeros, std::mt19937& random) {
  std::normal_distribution<double> normal;
  Matrix a(n, n);
  for (Index i = 0; i < a.size(); ++i) a.data()[i] = normal(random);
  const Eigen::HouseholderQR<Matrix> qr(a);
  const Matrix q = qr.householderQ();
  Vector lambda(n);
  for (Index i = 0; i < n; ++i) {
    lambda(i) = i < zeros ? 0.0 : std::pow(smallest, double(i - zeros) / double(std::max<Index>(1, n - zeros - 1)));
  }
  return q * lambda.asDiagonal() * q.transpose();
}

}  // namespace

// J Jᵀ given as a matrix, Jᵀ the identity: power_pinv_apply's Gram path then returns
// U Σ^{−1−κ} Uᵀ g, the part the ranks compute together.
class GivenGram final : public physgrad::JacobianOperator {
 public:
  explicit GivenGram(const Matrix& gram) : gram_(gram) {}
  Index rows() const override { return gram_.rows(); }
  Index cols() const override { return gram_.rows(); }
  Matrix gram() const override { return gram_; }
  Vector apply_transpose(const Vector& c) const override { return c; }
  Matrix materialize() const override { throw physgrad::Error("GivenGram: no J"); }
  Normal normal(const Vector&) const override { throw physgrad::Error("GivenGram: no J"); }

 private:
  const Matrix& gram_;
};

int main(int argc, char** argv) {
  const auto communicator = physgrad::mpi_world_communicator(&argc, &argv);
  physgrad::DistributedEigensolver* solver = communicator->eigensolver();
  if (solver == nullptr) {
    std::printf("no distributed eigensolver in this build\n");
    return 3;
  }
  std::mt19937 random(7);
  bool ok = true;
  struct Case {
    Index n;
    double smallest;
    Index zeros;
    double kappa, rcond;
  };
  for (const Case c : {Case{1, 1.0, 0, 0.5, 1e-6}, Case{7, 1e-3, 2, 0.5, 1e-6},
                       Case{200, 1e-4, 10, 0.5, 1e-3}, Case{333, 1e-6, 0, 1.0, 1e-4},
                       Case{1100, 1e-3, 0, 0.5, 1e-6}}) {
    const Matrix a = known_spectrum(c.n, c.smallest, c.zeros, random);
    Vector g(c.n);
    std::normal_distribution<double> normal;
    for (Index i = 0; i < c.n; ++i) g(i) = normal(random);
    physgrad::PowerPinvInfo reference_info;
    const Vector reference = physgrad::power_pinv_apply(
        GivenGram(a), g,
        {.cut = {.kappa = c.kappa, .rcond = c.rcond}, .backend = physgrad::PinvBackend::kGram},
        &reference_info);
    const std::vector<Index> columns =
        physgrad::block_cyclic_columns(c.n, solver->block(), solver->rank(), solver->size());
    Matrix local(c.n, static_cast<Index>(columns.size()));
    for (std::size_t s = 0; s < columns.size(); ++s) local.col(Index(s)) = a.col(columns[s]);
    physgrad::DistributedPowerInfo info;
    const physgrad::SpectralCut cut{.kappa = c.kappa, .rcond = reference_info.rcond_used};
    const Vector x =
        physgrad::distributed_truncated_power(*solver, std::move(local), c.n, g, cut, &info);
    const double difference = (x - reference).norm() / reference.norm();
    const bool same_everywhere = physgrad::same_on_all_ranks(
        *communicator, physgrad::hash_doubles(x.data(), static_cast<std::size_t>(x.size())));
    const bool good = difference <= 1e-10 && info.kept == reference_info.rank &&
                      std::abs(info.sigma_max - reference_info.sigma_max) <=
                          1e-12 * reference_info.sigma_max &&
                      same_everywhere;
    if (communicator->rank() == 0 || !good) {
      std::printf(
          "n %lld on %d ranks: kept %lld (one process %lld), sigma_max %.17g (%.17g), relative "
          "difference %.2e%s%s\n",
          static_cast<long long>(c.n), solver->size(), static_cast<long long>(info.kept),
          static_cast<long long>(reference_info.rank), info.sigma_max, reference_info.sigma_max,
          difference, same_everywhere ? "" : ", ranks differ", good ? "" : ": FAILED");
    }
    ok = ok && good;
  }
  return ok ? 0 : 1;
}
