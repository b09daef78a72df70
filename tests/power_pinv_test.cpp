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
#include "factored_jacobian.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

constexpr std::array<PinvBackend, 3> kBackends{PinvBackend::kSvd, PinvBackend::kGram,
                                               PinvBackend::kNormal};
constexpr std::array<double, 3> kKappas{1.0, 0.5, -1.0};
constexpr double kEps = std::numeric_limits<double>::epsilon();

using testing::factored;
using testing::Factored;
using testing::formula;
using testing::log_spaced;
using testing::random_orthonormal;
using testing::relative_error;

Vector apply(const Matrix& j, const Vector& g, double kappa, double rcond, PinvBackend backend,
             PowerPinvInfo* info = nullptr) {
  return power_pinv_apply(j, g, {.cut = {.kappa = kappa, .rcond = rcond}, .backend = backend}, info);
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
  expect_error([&] { power_pinv_apply(j, g, {.cut = {.rcond = 1.0}}); },
               "rcond must be in [0, 1), got 1");
  expect_error([&] { power_pinv_apply(j, g, {.cut = {.rcond = -0.1}}); }, "got -0.1");
  // J^{−κ} has no damping: a cut with one is refused, not applied on some paths only.
  expect_error([&] { power_pinv_apply(j, g, {.cut = {.rcond = 0.0, .damping = 0.5}}); },
               "power_pinv_apply: damping must be 0 (J^{−κ} is undamped), got 0.5");
  expect_error([&] { power_pinv_apply(j, g, {.cut = {.kappa = std::nan(""), .rcond = 1e-6}}); },
               "kappa must be finite");
  EXPECT_NO_THROW(power_pinv_apply(j, g, {.cut = {.rcond = 0.0}}));

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
    const PowerPinvOptions options{.cut = {.kappa = 0.5, .rcond = 1e-6}, .backend = backend};
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
  power_pinv_apply(wide, g, {.cut = {.kappa = 0.5, .rcond = 1e-6}});
  EXPECT_EQ(wide.calls, (std::vector<std::string>{"gram", "apply_transpose"}));
}

}  // namespace
}  // namespace physgrad
