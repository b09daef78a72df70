// Uses the installed library: a built-in simulator minimized with the physical gradient, and
// a pseudo-inverse through LAPACK, so every link dependency is needed.
#include <cstdio>

#include "physgrad/physgrad.hpp"  // the front door: every installed header it names must exist

int main() {
  const physgrad::DiagonalScale physics(physgrad::Vector{{1.0, 100.0}});
  const physgrad::L2Loss loss;
  const physgrad::Objective objective(physics, loss, physgrad::Vector::Zero(2));
  auto pg = physgrad::make_optimizer("pg", {{"lr", 0.5}});
  const auto summary = physgrad::minimize(*pg, objective, physgrad::Vector{{0.48, 0.84}},
                                          {.max_iterations = 50, .loss_tolerance = 1e-12});
  std::printf("pg %s in %d iterations\n", physgrad::to_string(summary.termination).c_str(),
              summary.iterations);

  const physgrad::Matrix j{{1.0, 2.0, 0.0}, {0.0, 1.0, 3.0}};
  const physgrad::Vector x = physgrad::power_pinv_apply(j, physgrad::Vector{{1.0, 1.0}});
  std::printf("J+ g residual %.1e\n", (j * x - physgrad::Vector{{1.0, 1.0}}).norm());
  return 0;
}
