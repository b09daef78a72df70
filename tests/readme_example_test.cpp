// The library example of README.md, kept compiling and true.
#include <gtest/gtest.h>

#include "physgrad/physgrad.hpp"

TEST(ReadmeExample, PhysicalGradientSolvesTheScaledToy) {
  physgrad::DiagonalScale physics(physgrad::Vector{{1.0, 100.0}});  // P(x) = (x₁, 100 x₂)
  physgrad::L2Loss loss;                                              // ½‖y − y*‖²
  physgrad::Objective objective(physics, loss, physgrad::Vector::Zero(2));
  auto pg = physgrad::make_optimizer("pg", {{"lr", 0.5}});
  auto summary = physgrad::minimize(*pg, objective, physgrad::Vector{{0.48, 0.84}},
                                    {.max_iterations = 50, .loss_tolerance = 1e-12});
  EXPECT_EQ(summary.termination, physgrad::Termination::kConverged);
  // x_k = (1 − η)^k x₀, so L_k = 0.25^k L₀ with L₀ = 3528.1152: 26 steps reach 1e-12.
  EXPECT_EQ(summary.iterations, 26);
}
