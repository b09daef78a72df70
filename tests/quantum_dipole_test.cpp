// Quantum dipole and fidelity loss: the Crank-Nicolson adjoint against central differences,
// unitarity, stationary eigenstates, the infidelity's derivatives and the shape checks.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/loss/fidelity.hpp"
#include "physgrad/physics/quantum_dipole.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

using testing::random_uniform;

// ⟨a|b⟩ in the real layout [Re …, Im …].
std::complex<double> inner(const Vector& a, const Vector& b) {
  const Index m = a.size() / 2;
  std::complex<double> sum = 0;
  for (Index j = 0; j < m; ++j) {
    sum += std::conj(std::complex<double>(a(j), a(m + j))) * std::complex<double>(b(j), b(m + j));
  }
  return sum;
}

TEST(QuantumDipole, DerivativesMatchFiniteDifferences) {
  std::mt19937_64 rng(3);
  const QuantumDipole physics;
  Vector random_state = random_uniform(rng, 28, 1, -1, 1);
  random_state /= random_state.norm();
  for (const Vector& psi0 : {dipole_eigenstate(1), random_state}) {
    const Vector u = random_uniform(rng, physics.input_dim(), 1, -2, 2);
    const DerivativeCheck check = check_derivatives(physics, u, psi0, 1e-6);
    EXPECT_TRUE(check.passed) << check.report();
  }
}

TEST(QuantumDipole, NormIsConservedUnderRandomControls) {
  std::mt19937_64 rng(5);
  const QuantumDipole physics;
  const Matrix u = random_uniform(rng, physics.input_dim(), 8, -2, 2);
  Matrix psi0 = random_uniform(rng, 28, 8, -1, 1);
  psi0.colwise().normalize();
  const Matrix psi = physics.forward_batch(u, psi0);
  for (Index b = 0; b < 8; ++b) EXPECT_NEAR(psi.col(b).squaredNorm(), 1.0, 1e-12);
  EXPECT_GT((psi - psi0).norm(), 0.1);  // the controls did act
}

TEST(QuantumDipole, EigenstatesOnlyRotateTheirPhase) {
  // −D₂ψ_n = E_n ψ_n with E_n = (2 − 2cos(πn/15))/dx²; each step multiplies ψ_n by
  // (1 − iθ)/(1 + iθ), θ = dt E_n/2.
  const QuantumDipole physics;
  const Vector u = Vector::Zero(physics.input_dim());
  const double dx = 2.0 / 15, dt = 0.05;
  for (const Index n : {1, 2, 5}) {
    const Vector psi_n = dipole_eigenstate(n);
    const Vector psi = physics.forward(u, psi_n);
    const double k = std::numbers::pi * static_cast<double>(n) / 15;
    const double energy = (2 - 2 * std::cos(k)) / (dx * dx);
    const std::complex<double> rho(1, -dt * energy / 2);
    const std::complex<double> phase = std::pow(rho / std::conj(rho), 384);
    EXPECT_NEAR(std::abs(inner(psi_n, psi)), 1.0, 1e-12) << "n " << n;
    EXPECT_NEAR(std::abs(inner(psi_n, psi) - phase), 0.0, 1e-11) << "n " << n;
  }
}

TEST(QuantumDipole, GroundStateHasInfidelityOneAgainstHigherStates) {
  const QuantumDipole physics;
  const Vector target = (dipole_eigenstate(2) + dipole_eigenstate(3)) / std::sqrt(2.0);
  const Vector psi = physics.forward(Vector::Zero(physics.input_dim()), dipole_eigenstate(1));
  EXPECT_NEAR(FidelityLoss().value(psi, target), 1.0, 1e-12);
  EXPECT_NEAR(target.squaredNorm(), 1.0, 1e-15);
}

TEST(QuantumDipole, RejectsBadShapesAndArguments) {
  const QuantumDipole physics;
  const Vector u = Vector::Zero(384), psi0 = dipole_eigenstate(1);
  EXPECT_THROW(physics.forward(Vector::Zero(383), psi0), Error);
  EXPECT_THROW(physics.forward(u), Error);  // the initial state is required
  EXPECT_THROW(physics.vjp(u, {}, psi0), Error);
  EXPECT_THROW(physics.forward(u, Vector::Zero(14)), Error);
  EXPECT_THROW(physics.vjp(u, psi0, Vector::Zero(14)), Error);
  EXPECT_THROW(QuantumDipole(QuantumDipoleConfig{2, 384, 0.05, 2.0}), Error);
  EXPECT_THROW(QuantumDipole(QuantumDipoleConfig{16, 384, 0.0, 2.0}), Error);
  EXPECT_THROW(dipole_eigenstate(0), Error);
  EXPECT_THROW(dipole_eigenstate(15), Error);
}

TEST(Fidelity, DerivativesMatchFiniteDifferences) {
  std::mt19937_64 rng(9);
  const FidelityLoss loss;
  const Vector y = random_uniform(rng, 28, 1, -1, 1), target = random_uniform(rng, 28, 1, -1, 1);
  const auto value = [&](const Vector& at) { return Vector::Constant(1, loss.value(at, target)); };
  const auto gradient = [&](const Vector& at) { return loss.gradient(at, target); };
  const Vector g = loss.gradient(y, target);
  const Matrix h = loss.hessian(y, target);
  EXPECT_LT((g - finite_difference_jacobian(value, y).transpose()).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((h - finite_difference_jacobian(gradient, y)).cwiseAbs().maxCoeff(), 1e-8);
  // The minimum-norm Newton step −H⁺g, and it reaches the stationary point a = b = 0.
  const Vector step = loss.newton_step(y, target);
  EXPECT_LT((step + h.completeOrthogonalDecomposition().solve(g)).norm(), 1e-12);
  EXPECT_NEAR(loss.value(y + step, target), 1.0, 1e-12);
}

TEST(Fidelity, ZeroForTheTargetTimesAPhase) {
  std::mt19937_64 rng(13);
  const FidelityLoss loss;
  Vector target = random_uniform(rng, 28, 1, -1, 1);
  target /= target.norm();
  for (const double phi : {0.0, 0.7, -2.9}) {
    const std::complex<double> phase = std::polar(1.0, phi);
    Vector y(28);
    for (Index j = 0; j < 14; ++j) {
      const std::complex<double> v = phase * std::complex<double>(target(j), target(14 + j));
      y(j) = v.real();
      y(14 + j) = v.imag();
    }
    EXPECT_NEAR(loss.value(y, target), 0.0, 1e-14) << "phi " << phi;
    // L is not bounded below in R^2M: only the norm-preserving directions are stationary,
    // the gradient points along −y (growing |ψ| beyond 1 lowers L further).
    EXPECT_LT((loss.gradient(y, target) + 2 * y).norm(), 1e-14) << "phi " << phi;
  }
  EXPECT_NEAR(loss.value(target, Vector::Zero(28)), 1.0, 1e-15);
}

TEST(Fidelity, RejectsOddOrMismatchedSizes) {
  const FidelityLoss loss;
  EXPECT_THROW(loss.value(Vector::Zero(3), Vector::Zero(3)), Error);
  EXPECT_THROW(loss.gradient(Vector::Zero(4), Vector::Zero(6)), Error);
  EXPECT_THROW(loss.hessian(Vector::Zero(5), Vector::Zero(5)), Error);
  EXPECT_THROW(loss.newton_step(Vector::Zero(4), Vector::Zero(2)), Error);
}

}  // namespace
}  // namespace physgrad
