// The truncated power-pseudo-inverse J^{−κ} g: every backend against the formula
// V diag(σ^{−κ}) Uᵀ g built from known factors, truncation, backend choice and input checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/inversion/power_pinv.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

constexpr std::array<PinvBackend, 3> kBackends{PinvBackend::kSvd, PinvBackend::kGram,
                                               PinvBackend::kNormal};
constexpr std::array<double, 3> kKappas{1.0, 0.5, -1.0};
constexpr double kEps = std::numeric_limits<double>::epsilon();

// n×k with orthonormal columns: the Q factor of a Householder QR of a random matrix.
Matrix random_orthonormal(Index n, Index k, unsigned seed) {
  const Eigen::HouseholderQR<Matrix> qr(testing::random_normal(n, k, seed));
  return qr.householderQ() * Matrix::Identity(n, k);
}

// count values from 1 down to lo, evenly spaced in log.
Vector log_spaced(Index count, double lo) {
  Vector s(count);
  for (Index k = 0; k < count; ++k) {
    s(k) = std::pow(lo, static_cast<double>(k) / static_cast<double>(count - 1));
  }
  return s;
}

// J = U diag(s) Vᵀ with known orthonormal U (rows × |s|) and V (cols × |s|).
struct Factored {
  Matrix u;
  Vector s;
  Matrix v;
  Matrix j;
};

Factored factored(Index rows, Index cols, const Vector& s, unsigned seed) {
  Factored f{random_orthonormal(rows, s.size(), seed), s,
             random_orthonormal(cols, s.size(), seed + 1), Matrix()};
  f.j = f.u * s.asDiagonal() * f.v.transpose();
  return f;
}

// V diag(s^{−κ}) Uᵀ g over s > rcond·max(s), from the known factors.
Vector formula(const Factored& f, const Vector& g, double kappa, double rcond) {
  const double cutoff = rcond * f.s.maxCoeff();
  Vector c = f.u.transpose() * g;
  for (Index i = 0; i < c.size(); ++i) c(i) = f.s(i) > cutoff ? c(i) * std::pow(f.s(i), -kappa) : 0;
  return f.v * c;
}

double relative_error(const Vector& x, const Vector& ref) { return (x - ref).norm() / ref.norm(); }

Vector apply(const Matrix& j, const Vector& g, double kappa, double rcond, PinvBackend backend,
             PowerPinvInfo* info = nullptr) {
  return power_pinv_apply(j, g, {kappa, rcond, backend}, info);
}

// Wide and tall shapes of a Jacobian with min(rows, cols) = 40.
constexpr std::array<std::array<Index, 2>, 2> kShapes{{{40, 90}, {90, 40}}};

TEST(PowerPinvBackends, MatchFormulaWhenModeratelyConditioned) {
  // Kept σ span three decades: the squared paths' error C·ε·(σ_max/σ_min)² is ~1e-9 here.
  unsigned seed = 1;
  for (const auto& [rows, cols] : kShapes) {
    const Factored f = factored(rows, cols, log_spaced(40, 1e-3), seed);
    const Vector g = testing::random_normal(rows, 1, seed + 2);
    seed += 3;
    for (const double kappa : kKappas) {
      const Vector ref = formula(f, g, kappa, 0);
      for (const PinvBackend backend : kBackends) {
        SCOPED_TRACE(to_string(backend) + " " + std::to_string(rows) + "x" +
                     std::to_string(cols) + " kappa " + std::to_string(kappa));
        const Vector x = apply(f.j, g, kappa, 1e-10, backend);
        EXPECT_LT(relative_error(x, ref), 1e-8);
        if (kappa == -1) {
          EXPECT_LT(relative_error(x, f.j.transpose() * g), 1e-8);
        }
      }
    }
  }
}

// The squared paths' error bound C·ε·σ_max²/σ_min,kept². Largest C measured over 200 random
// seeds × both shapes: 3.4 at four decades, 27 on the ill-conditioned spectrum below.
constexpr double kSquaringConstant = 50;

void expect_within_squaring_bound(const Vector& s, double rcond) {
  const double squared_rcond = std::max(rcond, kMinGramRcond);
  const Eigen::Array<bool, Eigen::Dynamic, 1> kept = s.array() > squared_rcond * s.maxCoeff();
  const double sigma_min_kept = kept.select(s.array(), s.maxCoeff()).minCoeff();
  const double bound = kSquaringConstant * kEps * std::pow(s.maxCoeff() / sigma_min_kept, 2);
  unsigned seed = 11;
  for (const auto& [rows, cols] : kShapes) {
    const Factored f = factored(rows, cols, s, seed);
    const Vector g = testing::random_normal(rows, 1, seed + 2);
    seed += 3;
    for (const double kappa : kKappas) {
      SCOPED_TRACE(std::to_string(rows) + "x" + std::to_string(cols) + " kappa " +
                   std::to_string(kappa));
      PowerPinvInfo info;
      EXPECT_LT(relative_error(apply(f.j, g, kappa, rcond, PinvBackend::kSvd, &info),
                               formula(f, g, kappa, rcond)),
                1e-8);
      EXPECT_EQ(info.rank, (s.array() > rcond * s.maxCoeff()).count());
      const Vector ref = formula(f, g, kappa, squared_rcond);
      for (const PinvBackend backend : {PinvBackend::kGram, PinvBackend::kNormal}) {
        EXPECT_LT(relative_error(apply(f.j, g, kappa, rcond, backend, &info), ref), bound)
            << to_string(backend);
        EXPECT_EQ(info.rank, kept.count()) << to_string(backend);
      }
    }
  }
}

TEST(PowerPinvBackends, FourDecadesWithinSquaringBound) {
  expect_within_squaring_bound(log_spaced(40, 1e-4), 1e-10);
}

TEST(PowerPinvBackends, IllConditionedSvdExactSquaredPathsWithinBound) {
  // σ from 10^{1/8} down to 1e-7 in quarter decades, rcond 1e-9: the SVD keeps all 29; the
  // squared paths clamp to 1e-7·σ_max, which falls half a step (in log) between the two
  // smallest σ, so rounding cannot decide which are kept.
  Vector s = log_spaced(29, 1e-7);
  s(0) = std::pow(10.0, 0.125);
  expect_within_squaring_bound(s, 1e-9);
}

TEST(PowerPinvBackends, RankDeficientResultHasNoNullComponent) {
  const Vector s = log_spaced(10, 1e-2);
  unsigned seed = 21;
  for (const auto& [rows, cols] : kShapes) {
    // Full orthonormal bases; J uses the first 10 columns, its other σ are exactly 0.
    const Matrix u = random_orthonormal(rows, rows, seed++);
    const Matrix v = random_orthonormal(cols, cols, seed++);
    const Matrix j = u.leftCols(10) * s.asDiagonal() * v.leftCols(10).transpose();
    const Vector g = testing::random_normal(rows, 1, seed++);
    const Vector shifted_g = g + u.rightCols(rows - 10) * testing::random_normal(rows - 10, 1, seed++);
    for (const double kappa : {1.0, 0.5}) {
      const Vector ref = apply(j, g, kappa, 1e-10, PinvBackend::kSvd);
      for (const PinvBackend backend : kBackends) {
        SCOPED_TRACE(to_string(backend) + " " + std::to_string(rows) + "x" +
                     std::to_string(cols) + " kappa " + std::to_string(kappa));
        PowerPinvInfo info;
        const Vector x = apply(j, g, kappa, 1e-10, backend, &info);
        EXPECT_EQ(info.rank, 10);
        EXPECT_LT(relative_error(x, ref), 1e-10);
        EXPECT_LT((v.rightCols(cols - 10).transpose() * x).norm() / x.norm(), 1e-10);
        EXPECT_LT(relative_error(apply(j, shifted_g, kappa, 1e-10, backend), x), 1e-10);
      }
    }
  }
}

TEST(PowerPinvTruncation, StrictAndRelativeToSigmaMax) {
  // Diagonal J (unsorted σ = 0.25, 1, 0.5, times a power of two) factors exactly, so a σ equal
  // to rcond·σ_max is exactly on the cutoff: it must be dropped.
  for (const double scale : {1.0, 8.0}) {
    for (const bool wide : {true, false}) {
      const Vector sigma = scale * Vector{{0.25, 1.0, 0.5}};
      Matrix j = Matrix::Zero(wide ? 3 : 5, wide ? 5 : 3);
      j.diagonal() = sigma;
      const Vector g = Vector::LinSpaced(j.rows(), 1.0, 2.0);
      for (const PinvBackend backend : kBackends) {
        for (const double kappa : {1.0, 0.5}) {
          SCOPED_TRACE(to_string(backend) + (wide ? " wide" : " tall") + " scale " +
                       std::to_string(scale) + " kappa " + std::to_string(kappa));
          PowerPinvInfo info;
          Vector expected = Vector::Zero(j.cols());
          expected(1) = g(1) * std::pow(sigma(1), -kappa);
          EXPECT_LT((apply(j, g, kappa, 0.5, backend, &info) - expected).norm(), 1e-15);
          EXPECT_EQ(info.rank, 1);
          EXPECT_EQ(info.sigma_max, scale);
          expected(2) = g(2) * std::pow(sigma(2), -kappa);
          EXPECT_LT((apply(j, g, kappa, 0.4999, backend, &info) - expected).norm(), 1e-15);
          EXPECT_EQ(info.rank, 2);
        }
      }
    }
  }
}

TEST(PowerPinvAuto, PicksBackendByShapeAndRcond) {
  // σ = 10^{−k/10}, k = 0…39; rcond = 10^{−1.95} keeps k = 0…19.
  const double rcond = std::pow(10.0, -1.95);
  for (const auto& [rows, cols] : kShapes) {
    const Factored f = factored(rows, cols, log_spaced(40, std::pow(10.0, -3.9)), 31);
    const Vector g = testing::random_normal(rows, 1, 33);
    const PinvBackend squared = rows <= cols ? PinvBackend::kGram : PinvBackend::kNormal;
    PowerPinvInfo info;
    const Vector x = apply(f.j, g, 1.0, rcond, PinvBackend::kAuto, &info);
    EXPECT_EQ(info.backend, squared);
    EXPECT_EQ(info.rank, 20);
    EXPECT_NEAR(info.sigma_max, 1.0, 1e-12);
    EXPECT_EQ(info.rcond_used, rcond);
    EXPECT_LT(relative_error(x, formula(f, g, 1.0, rcond)), 1e-10);

    apply(f.j, g, 1.0, kMinGramRcond, PinvBackend::kAuto, &info);
    EXPECT_EQ(info.backend, squared);
    apply(f.j, g, 1.0, 1e-9, PinvBackend::kAuto, &info);
    EXPECT_EQ(info.backend, PinvBackend::kSvd);
    EXPECT_EQ(info.rcond_used, 1e-9);
    EXPECT_EQ(info.rank, 40);
    apply(f.j, g, 1.0, 1e-9, squared, &info);  // forced: the floor applies and is reported
    EXPECT_EQ(info.backend, squared);
    EXPECT_EQ(info.rcond_used, kMinGramRcond);
  }
}

TEST(PowerPinvInvariance, RowAndColumnPermutations) {
  for (const auto& [rows, cols] : kShapes) {
    const Factored f = factored(rows, cols, log_spaced(40, 1e-3), 41);
    const Vector g = testing::random_normal(rows, 1, 43);
    std::vector<Index> row_order(static_cast<size_t>(rows));
    std::vector<Index> col_order(static_cast<size_t>(cols));
    std::iota(row_order.begin(), row_order.end(), 0);
    std::iota(col_order.begin(), col_order.end(), 0);
    std::mt19937 rng(44);
    std::shuffle(row_order.begin(), row_order.end(), rng);
    std::shuffle(col_order.begin(), col_order.end(), rng);
    const Matrix permuted_j = f.j(row_order, col_order);
    const Vector permuted_g = g(row_order);
    for (const PinvBackend backend : {PinvBackend::kAuto, PinvBackend::kSvd, PinvBackend::kGram,
                                      PinvBackend::kNormal}) {
      SCOPED_TRACE(to_string(backend) + " " + std::to_string(rows) + "x" + std::to_string(cols));
      const Vector x = apply(f.j, g, 0.5, 1e-6, backend);
      const Vector permuted_x = apply(permuted_j, permuted_g, 0.5, 1e-6, backend);
      Vector unpermuted_x(cols);
      unpermuted_x(col_order) = permuted_x;
      EXPECT_LT(relative_error(unpermuted_x, x), 1e-8);
    }
  }
}

// Expects f() to throw an Error whose message contains `needle`.
template <typename F>
void expect_error(F f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no Error thrown; expected one mentioning '" << needle << "'";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(PowerPinvValidation, RejectsBadInputAndNamesBackends) {
  const Matrix j = testing::random_normal(3, 4, 51);
  const Vector g = testing::random_normal(3, 1, 52);
  expect_error([&] { power_pinv_apply(j, Vector::Ones(4)); }, "3 rows but the vector has 4");
  Matrix nan_j = j;
  nan_j(1, 2) = std::nan("");
  expect_error([&] { power_pinv_apply(nan_j, g); }, "non-finite entry in the matrix");
  Vector inf_g = g;
  inf_g(0) = std::numeric_limits<double>::infinity();
  expect_error([&] { power_pinv_apply(j, inf_g); }, "non-finite entry in the vector");
  expect_error([&] { power_pinv_apply(j, g, {1.0, 1.0}); }, "rcond must be in [0, 1), got 1");
  expect_error([&] { power_pinv_apply(j, g, {1.0, -0.1}); }, "got -0.1");
  expect_error([&] { power_pinv_apply(j, g, {std::nan(""), 1e-6}); }, "kappa must be finite");
  EXPECT_NO_THROW(power_pinv_apply(j, g, {1.0, 0.0}));

  const Vector empty = power_pinv_apply(Matrix(0, 4), Vector(0));
  EXPECT_EQ(empty.size(), 4);
  EXPECT_TRUE(empty.isZero(0));

  for (const PinvBackend backend :
       {PinvBackend::kAuto, PinvBackend::kSvd, PinvBackend::kGram, PinvBackend::kNormal}) {
    EXPECT_EQ(parse_pinv_backend(to_string(backend)), backend);
  }
  EXPECT_EQ(to_string(PinvBackend::kGram), "gram");
  expect_error([] { parse_pinv_backend("cholesky"); },
               "'cholesky' (known: auto, svd, gram, normal)");
}

// An operator that says which of its forms the inversion asked for.
class CountingJacobian final : public JacobianOperator {
  // form(), noted as asked for under `name` (defined first: its return type is deduced).
  template <typename Form>
  auto asked(const char* name, const Form& form) const {
    calls.emplace_back(name);
    return form();
  }

 public:
  explicit CountingJacobian(const Matrix& j) : dense_(j) {}
  Index rows() const override { return dense_.rows(); }
  Index cols() const override { return dense_.cols(); }
  Matrix gram() const override { return asked("gram", [&] { return dense_.gram(); }); }
  Vector apply_transpose(const Vector& c) const override {
    return asked("apply_transpose", [&] { return dense_.apply_transpose(c); });
  }
  Matrix materialize() const override {
    return asked("materialize", [&] { return dense_.materialize(); });
  }
  Normal normal(const Vector& g) const override {
    return asked("normal", [&] { return dense_.normal(g); });
  }
  mutable std::vector<std::string> calls;

 private:
  DenseJacobian dense_;
};

TEST(PowerPinv, EachPathAsksTheOperatorForItsOneFormAndAgreesWithTheMatrix) {
  const Matrix j = testing::random_normal(6, 9, 11);
  const Vector g = testing::random_normal(6, 1, 12).col(0);
  const std::vector<std::pair<PinvBackend, std::vector<std::string>>> paths = {
      {PinvBackend::kGram, {"gram", "apply_transpose"}},
      {PinvBackend::kNormal, {"normal"}},
      {PinvBackend::kSvd, {"materialize"}}};
  for (const auto& [backend, forms] : paths) {
    const PowerPinvOptions options{0.5, 1e-6, backend};
    CountingJacobian counted(j);
    PowerPinvInfo info;
    PowerPinvTiming timing;
    const Vector result = power_pinv_apply(counted, g, options, &info, &timing);
    EXPECT_EQ(counted.calls, forms) << to_string(backend);
    EXPECT_EQ(info.backend, backend);
    EXPECT_EQ(info.rank, 6);
    EXPECT_GE(timing.forming_seconds, 0.0);
    EXPECT_LT((result - power_pinv_apply(j, g, options)).norm(), 1e-12 * result.norm())
        << to_string(backend);
  }
  // kAuto on a wide J at this cutoff: the Gram path.
  CountingJacobian wide(j);
  power_pinv_apply(wide, g, {0.5, 1e-6});
  EXPECT_EQ(wide.calls, (std::vector<std::string>{"gram", "apply_transpose"}));
}

// The precision and eigensolver of the Gram path.

constexpr double kFloatEps = std::numeric_limits<float>::epsilon();

PowerPinvOptions eigensolve(double kappa, double rcond, PinvPrecision precision,
                            PinvEigensolver eigensolver, const PowerPinvInfo* previous = nullptr) {
  return {.kappa = kappa,
          .rcond = rcond,
          .backend = PinvBackend::kGram,
          .precision = precision,
          .eigensolver = eigensolver,
          .previous = previous};
}

// A well-conditioned J (σ from 1 to 0.1, kept condition 10): the float check passes, auto runs
// float, and the result agrees with double within the float eigenvalue bound: each kept
// λ = σ² carries an error ≲ δ = √n·ε_f·λ_max, i.e. δ/λ ≤ √n·ε_f·cond² relative, which the step
// inherits with the factor (1+κ)/2 ≤ 1 (and the eigenvectors' rotation by about as much).
TEST(PowerPinvPrecision, FloatAgreesWithDoubleWithinItsBoundOnAWellConditionedJ) {
  const Index rows = 200, cols = 500;
  const Factored f = factored(rows, cols, log_spaced(rows, 0.1), 31);
  const Vector g = testing::random_normal(rows, 1, 33);
  const double cond = 10, bound = std::sqrt(static_cast<double>(rows)) * kFloatEps * cond * cond;
  for (const PinvEigensolver solver :
       {PinvEigensolver::kFull, PinvEigensolver::kSubset, PinvEigensolver::kTridiagonal}) {
    SCOPED_TRACE(to_string(solver));
    PowerPinvInfo in_double, in_auto;
    const Vector x_double = power_pinv_apply(
        f.j, g, eigensolve(0.5, 1e-6, PinvPrecision::kDouble, solver), &in_double);
    const Vector x_auto = power_pinv_apply(
        f.j, g, eigensolve(0.5, 1e-6, PinvPrecision::kAuto, solver), &in_auto);
    EXPECT_LT(relative_error(x_double, formula(f, g, 0.5, 0)), 1e-12);
    EXPECT_EQ(in_double.precision, PinvPrecision::kDouble);
    EXPECT_TRUE(in_double.float_resolves);
    EXPECT_EQ(in_auto.precision, PinvPrecision::kFloat);
    EXPECT_EQ(in_auto.eigensolver, solver);
    EXPECT_FALSE(in_auto.float_rejected);
    EXPECT_EQ(in_auto.rank, rows);
    EXPECT_NEAR(kept_condition(in_auto), cond, 1e-3 * cond);
    const double error = relative_error(x_auto, x_double);
    EXPECT_LT(error, bound) << "bound " << bound;
    EXPECT_GT(error, 0.0);  // it did run in float
  }
}

// Singular values spanning 1 … 1e-6 (λ down to 1e-12·λ_max, far below float's δ ≈ 2e-6·λ_max):
// auto tries float, the check rejects it and the result is the double one, bit for bit; forced
// float is off by far more than a step may be. With a previous spectrum that float does not
// resolve, auto goes straight to double.
TEST(PowerPinvPrecision, AutoFallsBackToDoubleOnAnIllConditionedJ) {
  const Index rows = 200, cols = 500;
  const Factored f = factored(rows, cols, log_spaced(rows, 1e-6), 41);
  const Vector g = testing::random_normal(rows, 1, 43);
  for (const PinvEigensolver solver : {PinvEigensolver::kFull, PinvEigensolver::kTridiagonal}) {
    SCOPED_TRACE(to_string(solver));
    PowerPinvInfo in_double, in_auto, in_float;
    const Vector x_double = power_pinv_apply(
        f.j, g, eigensolve(0.5, 1e-7, PinvPrecision::kDouble, solver), &in_double);
    const Vector x_auto =
        power_pinv_apply(f.j, g, eigensolve(0.5, 1e-7, PinvPrecision::kAuto, solver), &in_auto);
    const Vector x_float = power_pinv_apply(
        f.j, g, eigensolve(0.5, 1e-7, PinvPrecision::kFloat, solver), &in_float);
    EXPECT_FALSE(in_double.float_resolves);
    EXPECT_TRUE(in_auto.float_rejected);
    EXPECT_EQ(in_auto.precision, PinvPrecision::kDouble);
    EXPECT_TRUE(x_auto == x_double);
    EXPECT_EQ(in_double.rank, rows);
    EXPECT_NEAR(kept_condition(in_double), 1e6, 1e3);
    EXPECT_EQ(in_float.precision, PinvPrecision::kFloat);
    EXPECT_GT(relative_error(x_float, x_double), 0.1);

    PowerPinvInfo after;
    const Vector x_after = power_pinv_apply(
        f.j, g, eigensolve(0.5, 1e-7, PinvPrecision::kAuto, solver, &in_double), &after);
    EXPECT_FALSE(after.float_rejected);
    EXPECT_EQ(after.precision, PinvPrecision::kDouble);
    EXPECT_TRUE(x_after == x_double);
  }
}

// The check itself: δ = √n·ε_f·λ_max; kept values must reach max(1e3·δ, cut² + δ), dropped ones
// stay below cut² − δ.
TEST(PowerPinvPrecision, TheFloatCheckSeparatesResolvedFromUnresolvedSpectra) {
  const Index n = 100;
  const double delta = 10 * kFloatEps;  // √100·ε_f·λ_max with λ_max = 1
  Vector lambda = Vector::LinSpaced(n, 1e-2, 1.0);
  EXPECT_TRUE(float_resolves_spectrum(lambda, n, 1e-6));
  lambda(0) = 0.5 * kFloatAccuracy * delta;  // kept but not accurate enough
  EXPECT_FALSE(float_resolves_spectrum(lambda, n, 1e-6));
  lambda(0) = 0;  // an exact zero: dropped clearly only when the cut is above δ
  EXPECT_FALSE(float_resolves_spectrum(lambda, n, 1e-6));
  EXPECT_TRUE(float_resolves_spectrum(lambda, n, 0.1));
  lambda(0) = 0.01 - 0.5 * delta;  // within δ of the cut² = 0.01
  EXPECT_FALSE(float_resolves_spectrum(lambda, n, 0.1));
}

// Half the singular values far below the cut: the subset eigensolver (dsyevr above a lower
// bound of the cut) keeps the same directions and agrees with dsyevd; auto picks it when the
// previous call kept at most kSubsetKeptFraction of n, the tridiagonal solver otherwise.
TEST(PowerPinvEigensolver, SubsetAgreesWithFullAndAutoFollowsThePreviousRank) {
  const Index rows = 120, cols = 300;
  Vector s = log_spaced(rows, 1e-2);
  s.tail(rows / 2).setConstant(1e-9);
  const Factored f = factored(rows, cols, s, 51);
  const Vector g = testing::random_normal(rows, 1, 53);
  PowerPinvInfo full, subset;
  const Vector x_full = power_pinv_apply(
      f.j, g, eigensolve(0.5, 1e-6, PinvPrecision::kDouble, PinvEigensolver::kFull), &full);
  const Vector x_subset = power_pinv_apply(
      f.j, g, eigensolve(0.5, 1e-6, PinvPrecision::kDouble, PinvEigensolver::kSubset), &subset);
  EXPECT_EQ(full.eigensolver, PinvEigensolver::kFull);
  EXPECT_EQ(subset.eigensolver, PinvEigensolver::kSubset);
  EXPECT_EQ(full.rank, rows / 2);
  EXPECT_EQ(subset.rank, rows / 2);
  EXPECT_NEAR(subset.sigma_max, full.sigma_max, 1e-14 * full.sigma_max);
  EXPECT_LT(relative_error(x_subset, x_full), 1e-12);
  EXPECT_LT(relative_error(x_full, formula(f, g, 0.5, 1e-6)), 1e-10);

  PowerPinvInfo chosen;
  PowerPinvInfo previous = full;
  previous.rank = static_cast<Index>(kSubsetKeptFraction * static_cast<double>(rows));
  power_pinv_apply(f.j, g,
                   eigensolve(0.5, 1e-6, PinvPrecision::kDouble, PinvEigensolver::kAuto, &previous),
                   &chosen);
  EXPECT_EQ(chosen.eigensolver, PinvEigensolver::kSubset);
  previous.rank += 1;
  power_pinv_apply(f.j, g,
                   eigensolve(0.5, 1e-6, PinvPrecision::kDouble, PinvEigensolver::kAuto, &previous),
                   &chosen);
  EXPECT_EQ(chosen.eigensolver, PinvEigensolver::kTridiagonal);
  power_pinv_apply(f.j, g, eigensolve(0.5, 1e-6, PinvPrecision::kDouble, PinvEigensolver::kAuto),
                   &chosen);
  EXPECT_EQ(chosen.eigensolver, PinvEigensolver::kTridiagonal);  // no history: every eigenvalue
}

// The tridiagonal eigensolver (reduction, QL rotations applied to the one vector) against the
// eigenvectors of dsyevd and the closed form V Σ^{−κ} Uᵀ g: singular values spanning 1 … 1e-5
// with a quarter of them exactly zero (dropped by the cut), for GN, HIG and Jᵀ; on the normal
// path too (a tall J).
TEST(PowerPinvEigensolver, TridiagonalAgreesWithFullAndTheClosedForm) {
  const Index rows = 160, cols = 400;
  Vector s = log_spaced(rows, 1e-5);
  s.tail(rows / 4).setZero();
  const Factored f = factored(rows, cols, s, 61);
  const Vector g = testing::random_normal(rows, 1, 63);
  for (const double kappa : {1.0, 0.5, -1.0}) {
    SCOPED_TRACE(kappa);
    PowerPinvInfo full, tridiagonal;
    const Vector x_full = power_pinv_apply(
        f.j, g, eigensolve(kappa, 1e-6, PinvPrecision::kDouble, PinvEigensolver::kFull), &full);
    const Vector x_tridiagonal = power_pinv_apply(
        f.j, g, eigensolve(kappa, 1e-6, PinvPrecision::kDouble, PinvEigensolver::kTridiagonal),
        &tridiagonal);
    EXPECT_EQ(tridiagonal.eigensolver, PinvEigensolver::kTridiagonal);
    EXPECT_EQ(tridiagonal.rank, rows - rows / 4);
    EXPECT_EQ(full.rank, tridiagonal.rank);
    EXPECT_NEAR(tridiagonal.sigma_max, 1.0, 1e-14);
    EXPECT_NEAR(tridiagonal.sigma_min_kept, full.sigma_min_kept, 1e-9 * full.sigma_min_kept);
    // ε·(σ_max/σ_min,kept)² ≈ 7e-9 (σ_min,kept ≈ 1.8e-4) is the Gram path's stated accuracy.
    EXPECT_LT(relative_error(x_tridiagonal, formula(f, g, kappa, 1e-6)), 1e-8);
    EXPECT_LT(relative_error(x_tridiagonal, x_full), 1e-8);
  }
  // Every σ kept down to 1e-5: the result is dominated by the smallest eigenvalues of J Jᵀ, and
  // the tridiagonal eigensolver resolves them as well as dsyevd does (QL on the Gram matrix's
  // tridiagonal form the other way up was ~10× less accurate).
  const Factored graded = factored(rows, cols, log_spaced(rows, 1e-5), 67);
  const Vector x_exact = formula(graded, g, 0.5, 1e-7);
  const double error_full = relative_error(
      power_pinv_apply(graded.j, g,
                       eigensolve(0.5, 1e-7, PinvPrecision::kDouble, PinvEigensolver::kFull)),
      x_exact);
  const double error_tridiagonal = relative_error(
      power_pinv_apply(graded.j, g,
                       eigensolve(0.5, 1e-7, PinvPrecision::kDouble, PinvEigensolver::kTridiagonal)),
      x_exact);
  EXPECT_LT(error_tridiagonal, 2 * error_full) << "dsyevd's error " << error_full;

  const Matrix tall = f.j.transpose();
  const Vector h = testing::random_normal(cols, 1, 65);
  PowerPinvOptions normal = eigensolve(0.5, 1e-6, PinvPrecision::kDouble,
                                       PinvEigensolver::kTridiagonal);
  normal.backend = PinvBackend::kNormal;
  const Vector x_normal = power_pinv_apply(tall, h, normal);
  normal.backend = PinvBackend::kSvd;
  EXPECT_LT(relative_error(x_normal, power_pinv_apply(tall, h, normal)), 1e-8);
}

TEST(PowerPinvPrecision, NamesRoundTripAndUnknownOnesAreErrors) {
  for (const PinvPrecision p : {PinvPrecision::kAuto, PinvPrecision::kDouble, PinvPrecision::kFloat}) {
    EXPECT_EQ(parse_pinv_precision(to_string(p)), p);
  }
  for (const PinvEigensolver e :
       {PinvEigensolver::kAuto, PinvEigensolver::kFull, PinvEigensolver::kSubset,
        PinvEigensolver::kTridiagonal}) {
    EXPECT_EQ(parse_pinv_eigensolver(to_string(e)), e);
  }
  EXPECT_THROW(parse_pinv_precision("half"), Error);
  EXPECT_THROW(parse_pinv_eigensolver("lanczos"), Error);
}

}  // namespace
}  // namespace physgrad
