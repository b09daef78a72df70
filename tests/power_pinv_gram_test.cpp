// The Gram path of the power-pseudo-inverse: float against double precision within the float
// eigenvalue bound, the fallback to double, and the subset and tridiagonal eigensolvers against the
// full one and the closed form V diag(σ^{−κ}) Uᵀ g.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "physgrad/error.hpp"
#include "physgrad/inversion/power_pinv.hpp"
#include "factored_jacobian.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

using testing::factored;
using testing::Factored;
using testing::formula;
using testing::log_spaced;
using testing::relative_error;

constexpr double kFloatEps = std::numeric_limits<float>::epsilon();

PowerPinvOptions eigensolve(double kappa, double rcond, PinvPrecision precision,
                            PinvEigensolver eigensolver, const PowerPinvInfo* previous = nullptr) {
  return {.cut = {.kappa = kappa, .rcond = rcond},
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
  EXPECT_TRUE(float_resolves_spectrum(lambda, n, {.rcond = 1e-6}));
  lambda(0) = 0.5 * kFloatAccuracy * delta;  // kept but not accurate enough
  EXPECT_FALSE(float_resolves_spectrum(lambda, n, {.rcond = 1e-6}));
  lambda(0) = 0;  // an exact zero: dropped clearly only when the cut is above δ
  EXPECT_FALSE(float_resolves_spectrum(lambda, n, {.rcond = 1e-6}));
  EXPECT_TRUE(float_resolves_spectrum(lambda, n, {.rcond = 0.1}));
  lambda(0) = 0.01 - 0.5 * delta;  // within δ of the cut² = 0.01
  EXPECT_FALSE(float_resolves_spectrum(lambda, n, {.rcond = 0.1}));
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
