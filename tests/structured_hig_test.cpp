// The structured HIG rules against the exact step where their structure is exact: Kronecker
// factors on a single dense layer with identity physics (JᵀJ = (Σ āāᵀ) ⊗ I), Lanczos with as many
// steps as J has rows; the Lanczos helper on matrices of known spectrum; the factors' running
// average, refresh schedule and checkpoint state.
#include <gtest/gtest.h>

#include <cmath>

#include "learning_fixture.hpp"
#include "physgrad/error.hpp"
#include "physgrad/inversion/lanczos.hpp"
#include "physgrad/io/serialize.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;

double relative_difference(const Vector& a, const Vector& b) { return (a - b).norm() / b.norm(); }

double cosine(const Vector& a, const Vector& b) { return a.dot(b) / (a.norm() * b.norm()); }

// f(A) b with f(λ) = λ^{−p} on λ > cut·λ_max from A's eigendecomposition.
Vector eigen_function(const Matrix& a, const Vector& b, double p, double cut) {
  const Eigen::SelfAdjointEigenSolver<Matrix> eigen(a);
  const Vector& lambda = eigen.eigenvalues();
  Vector weights = Vector::Zero(lambda.size());
  for (Index i = 0; i < lambda.size(); ++i) {
    if (lambda(i) > cut * lambda.maxCoeff()) weights(i) = std::pow(lambda(i), -p);
  }
  return eigen.eigenvectors() * weights.asDiagonal() * eigen.eigenvectors().transpose() * b;
}

// A = V diag(λ) Vᵀ with λ from 1 down to 1e-3 and V orthonormal (QR of a random matrix).
Matrix known_spectrum(Index n, Matrix* vectors) {
  const Eigen::HouseholderQR<Matrix> qr(testing::random_normal(n, n, 7));
  *vectors = qr.householderQ() * Matrix::Identity(n, n);
  const Vector lambda = Vector::LinSpaced(n, 0.0, -3.0).unaryExpr([](double e) {
    return std::pow(10.0, e);
  });
  return *vectors * lambda.asDiagonal() * vectors->transpose();
}

TEST(LanczosFunction, IsExactWithNStepsAndConvergesBefore) {
  constexpr Index kN = 30;
  Matrix v;
  const Matrix a = known_spectrum(kN, &v);
  const Vector b = testing::random_normal(kN, 1, 3);
  const auto power = [](const Vector& theta) {
    return Vector(theta.array().pow(-0.75));
  };
  const Vector exact = eigen_function(a, b, 0.75, 0.0);
  const auto multiply = [&a](const Vector& x) { return Vector(a * x); };
  double previous = kInf;
  for (const Index steps : {5, 10, 20, 30}) {
    const LanczosApproximation l = lanczos_function(multiply, b, steps, power);
    EXPECT_EQ(l.steps, steps);
    const Vector approx = l.basis * l.coefficients;
    const double error = relative_difference(approx, exact);
    EXPECT_LT(error, previous) << steps;
    previous = error;
    // Q is orthonormal.
    EXPECT_LT((l.basis.transpose() * l.basis - Matrix::Identity(steps, steps)).norm(), 1e-13);
  }
  EXPECT_LT(previous, 1e-12);
  // Asking for more steps than n makes n.
  EXPECT_EQ(lanczos_function(multiply, b, 50, power).steps, kN);
}

TEST(LanczosFunction, StopsWhenTheKrylovSpaceIsExhausted) {
  constexpr Index kN = 20;
  Matrix v;
  const Matrix a = known_spectrum(kN, &v);
  // b in the span of three eigenvectors: three steps reach f(A) b exactly.
  const Vector b = v.col(2) - 2 * v.col(9) + 0.5 * v.col(17);
  const auto power = [](const Vector& theta) { return Vector(theta.array().pow(-1.0)); };
  const LanczosApproximation l =
      lanczos_function([&a](const Vector& x) { return Vector(a * x); }, b, kN, power);
  EXPECT_EQ(l.steps, 3);
  EXPECT_LT(relative_difference(l.basis * l.coefficients, eigen_function(a, b, 1.0, 0.0)), 1e-12);
  // A zero b takes no step; bad arguments are named.
  EXPECT_EQ(lanczos_function([&a](const Vector& x) { return Vector(a * x); }, Vector::Zero(kN), 5,
                             power)
                .steps,
            0);
  EXPECT_THROW(lanczos_function([](const Vector& x) { return x; }, b, 0, power), Error);
  EXPECT_THROW(lanczos_function([](const Vector& x) { return Vector(x.head(3)); }, b, 4, power),
               Error);
  EXPECT_THROW(lanczos_function([](const Vector& x) { return Vector(x * NAN); }, b, 4, power),
               NumericalError);
}

// x ↦ W x + b with identity output and identity physics: JᵀJ = (Σ āāᵀ) ⊗ I exactly.
struct SingleDenseLayer {
  DiagonalScale physics{Vector::Ones(3)};
  L2Loss loss{1.0};
  LearningProblem problem{&physics, &loss};
  Mlp network{{4, 3}, Activation::kIdentity, Activation::kIdentity};
  Dataset data;

  explicit SingleDenseLayer(Index batch) {
    network.initialize(2);
    network.bias(0) << 0.1, -0.2, 0.3;
    data.inputs = testing::random_normal(4, batch, 5);
    data.targets = testing::random_normal(3, batch, 6);
  }
  BatchState evaluate(MlpCache& cache) const {
    return evaluate_batch(network, problem, data, UpdateNeed::kStackedJacobian, cache);
  }
};

// B = 3 < 5 inputs (with the bias): A is singular, the cut drops its null space as HIG's drops
// J's; B = 8: A is regular, and J (24 × 15) is tall (the normal path of the exact step).
TEST(KroneckerHig, IsTheExactStepOnASingleDenseLayerWithIdentityPhysics) {
  for (const Index batch : {3, 8}) {
    const SingleDenseLayer s(batch);
    MlpCache cache;
    const BatchState state = s.evaluate(cache);
    for (const double kappa : {0.5, 1.0}) {
      HigUpdate exact({.lr = 0.7, .cut = {.kappa = kappa, .rcond = 1e-6}});
      KroneckerHigUpdate kronecker({.lr = 0.7, .cut = {.kappa = kappa, .rcond = 1e-6, .damping = 0}});
      const Vector expected = exact.step(state).delta;
      EXPECT_LT(relative_difference(kronecker.step(state).delta, expected), 1e-10)
          << "batch " << batch << ", κ " << kappa;
      // With damping it is not.
      KroneckerHigUpdate damped({.lr = 0.7, .cut = {.kappa = kappa, .rcond = 1e-6, .damping = 0.1}});
      EXPECT_GT(relative_difference(damped.step(state).delta, expected), 1e-3);
    }
  }
}

// On a network with a hidden layer and nonlinear physics the factorization is an approximation:
// the step differs from the exact one, yet points downhill.
TEST(KroneckerHig, ApproximatesTheExactStepElsewhere) {
  const NetworkThroughPhysics s(6);
  MlpCache cache;
  const BatchState state = s.evaluate(UpdateNeed::kStackedJacobian, cache);
  const Vector exact = HigUpdate({.lr = 1.0, .cut = {.kappa = 0.5, .rcond = 1e-6}}).step(state).delta;
  const Vector approx =
      KroneckerHigUpdate({.cut = {.kappa = 0.5, .rcond = 1e-6, .damping = 0}}).step(state).delta;
  EXPECT_GT(relative_difference(approx, exact), 1e-3);
  const Vector gradient = state.jacobian->apply_transpose(state.loss_gradient_y);
  EXPECT_LT(approx.dot(gradient), 0.0);
}

// q = B·m Lanczos steps reproduce the exact step on its Gram path, which decomposes the same
// J Jᵀ: with 12 rows and 32 weights, and where J Jᵀ is singular (48 rows, 32 weights: the
// Krylov space ends after 32 steps). Both round to ~ε·(σ_max/σ_min,kept)², so τ = 1e-3 keeps
// the kept condition below 10³ (at τ = 1e-4 it is 8.6e3 for 48 rows and the two agree to 1e-9).
TEST(LanczosHig, WithAsManyStepsAsRowsIsTheExactStep) {
  for (const Index batch : {6, 24}) {
    const NetworkThroughPhysics s(batch);
    MlpCache cache;
    const BatchState state = s.evaluate(UpdateNeed::kStackedJacobian, cache);
    const auto rows = static_cast<int>(state.jacobian->rows());
    for (const double kappa : {0.5, 1.0}) {
      const Vector expected =
          HigUpdate({.lr = 0.3, .cut = {.kappa = kappa, .rcond = 1e-3}, .backend = PinvBackend::kGram})
              .step(state)
              .delta;
      LanczosHigUpdate full({.lr = 0.3, .cut = {.kappa = kappa, .rcond = 1e-3}, .products = rows});
      EXPECT_LT(relative_difference(full.step(state).delta, expected), 1e-10)
          << "batch " << batch << ", κ " << kappa;
      // Fewer steps: an approximation, closer with more of them.
      LanczosHigUpdate two({.lr = 0.3, .cut = {.kappa = kappa, .rcond = 1e-3}, .products = 2});
      LanczosHigUpdate six({.lr = 0.3, .cut = {.kappa = kappa, .rcond = 1e-3}, .products = 6});
      const double c2 = cosine(two.step(state).delta, expected);
      const double c6 = cosine(six.step(state).delta, expected);
      EXPECT_LT(c2, 1 - 1e-6);
      EXPECT_LT(c2, c6);
      EXPECT_EQ(six.step_info().at("lanczos_steps"), 6);
    }
  }
}

TEST(KroneckerHig, RefreshesTheFactorsEveryKStepsAsARunningAverage) {
  NetworkThroughPhysics s(8);
  KroneckerHigUpdate rule({.lr = 0.1, .refresh = 3, .factor_decay = 0.25});
  std::vector<UpdateNeed> needs;
  std::vector<std::vector<DenseLayerFactors>> refreshed;
  MlpCache cache;
  for (int k = 0; k < 7; ++k) {
    needs.push_back(rule.need());
    const BatchState state = s.evaluate(rule.need(), cache);
    if (rule.need() == UpdateNeed::kStackedJacobian) {
      refreshed.push_back(state.jacobian->dense_layer_factors());
    }
    s.network.parameters() += rule.step(state).delta;
  }
  using N = UpdateNeed;
  EXPECT_EQ(needs, (std::vector<N>{N::kStackedJacobian, N::kGradient, N::kGradient,
                                   N::kStackedJacobian, N::kGradient, N::kGradient,
                                   N::kStackedJacobian}));
  // After three refreshes: F = ¼(¼F₀ + ¾F₁) + ¾F₂, A per sample (F/B), S summed.
  const nlohmann::json state = rule.state();
  EXPECT_EQ(state.at("steps"), 7);
  for (std::size_t l = 0; l < 2; ++l) {
    const auto averaged = [&](Matrix DenseLayerFactors::*member, double scale) {
      return Matrix(scale * (0.25 * (0.25 * (refreshed[0][l].*member) +
                                     0.75 * (refreshed[1][l].*member)) +
                             0.75 * (refreshed[2][l].*member)));
    };
    const Matrix a = averaged(&DenseLayerFactors::input_gram, 1.0 / 8);
    const Matrix g = averaged(&DenseLayerFactors::cotangent_gram, 1.0);
    const nlohmann::json& saved = state.at("layers").at(l);
    const Vector saved_a = vector_from_json(saved, "input_factor");
    const Vector saved_g = vector_from_json(saved, "cotangent_factor");
    EXPECT_LT((saved_a - a.reshaped()).norm(), 1e-14 * a.norm());
    EXPECT_LT((saved_g - g.reshaped()).norm(), 1e-14 * g.norm());
  }
  // reset() starts over.
  rule.reset();
  EXPECT_TRUE(rule.state().is_null());
  EXPECT_EQ(rule.need(), UpdateNeed::kStackedJacobian);
}

// A rule restored from the JSON text of state() makes the same steps, bit for bit, as the one
// that saved it; a state that does not fit the network is refused.
TEST(KroneckerHig, ItsStateRestoresTheSameStepsAndBadStatesAreRefused) {
  NetworkThroughPhysics s(8);
  KroneckerHigUpdate first({.lr = 0.1, .refresh = 3, .factor_decay = 0.5});
  MlpCache cache;
  for (int k = 0; k < 5; ++k) {
    s.network.parameters() += first.step(s.evaluate(first.need(), cache)).delta;
  }
  KroneckerHigUpdate second({.lr = 0.1, .refresh = 3, .factor_decay = 0.5});
  const Index count = s.network.num_parameters();
  second.restore(nlohmann::json::parse(first.state().dump()), count);
  EXPECT_EQ(second.need(), first.need());
  for (int k = 0; k < 4; ++k) {
    const BatchState state = s.evaluate(first.need(), cache);
    const Vector a = first.step(state).delta, b = second.step(state).delta;
    EXPECT_TRUE(a == b) << k;
    s.network.parameters() += a;
  }
  nlohmann::json bad = first.state();
  bad["layers"][0]["inputs"] = 3;  // the factor no longer fits
  EXPECT_THROW(second.restore(bad, count), Error);
  bad = first.state();
  bad["layers"].erase(1);  // the layers no longer cover θ
  EXPECT_THROW(second.restore(bad, count), Error);
  bad = first.state();
  bad["layers"][1]["cotangent_factor"][0] = "x";
  EXPECT_THROW(second.restore(bad, count), Error);
  EXPECT_THROW(second.restore(first.state(), count - 1), Error);
}

TEST(StructuredHig, NeedTheNetworksLayersAndNameWhatIsMissing) {
  const NetworkThroughPhysics s(4);
  MlpCache cache;
  BatchState state = s.evaluate(UpdateNeed::kGradient, cache);
  EXPECT_THROW(KroneckerHigUpdate().step(state), Error);  // refreshing without a Jacobian
  EXPECT_THROW(LanczosHigUpdate().step(state), Error);
  EXPECT_EQ(make_learning_update("kfac")->id(), "kfac");
  EXPECT_EQ(make_learning_update("kfac-hig")->id(), "kfac-hig");
  EXPECT_EQ(make_learning_update("lanczos-gn")->id(), "lanczos-gn");
  EXPECT_EQ(make_learning_update("lanczos-hig", {{"products", 7}})->params().at("products"), 7);
  EXPECT_THROW(make_learning_update("lanczos-hig", {{"products", 0}}), Error);
  EXPECT_THROW(make_learning_update("kfac", {{"factor_decay", 1.0}}), Error);
  EXPECT_EQ(settings_source("kfac-hig"), "hig");
  EXPECT_EQ(settings_source("lanczos-gn"), "gn");
  EXPECT_EQ(settings_source("adam"), "adam");
}

}  // namespace
}  // namespace physgrad
