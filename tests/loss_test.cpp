#include <gtest/gtest.h>

#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"

namespace physgrad {
namespace {

TEST(L2Loss, ValueGradientHessianAndNewtonStep) {
  const L2Loss loss(2.0);
  const Vector y{{3.0, 9.0}};
  const Vector target = Vector::Zero(2);
  EXPECT_DOUBLE_EQ(loss.value(y, target), 90.0);  // y0² + y1², the comparison notebook's L
  EXPECT_TRUE(loss.gradient(y, target).isApprox(Vector{{6.0, 18.0}}));
  EXPECT_TRUE(loss.hessian(y, target).isApprox(2.0 * Matrix::Identity(2, 2)));
  EXPECT_TRUE(loss.newton_step(y, target).isApprox(-y));
}

TEST(L2Loss, DefaultNewtonStepAgreesWithOverride) {
  const L2Loss loss(0.5);
  const Vector y{{1.0, -2.0, 0.5}};
  const Vector target{{0.0, 1.0, 2.0}};
  EXPECT_TRUE(loss.Loss::newton_step(y, target).isApprox(loss.newton_step(y, target), 1e-12));
}

TEST(L2Loss, RejectsBadWeightAndShapes) {
  EXPECT_THROW(L2Loss(0.0), Error);
  EXPECT_THROW(L2Loss(std::nan("")), Error);
  const L2Loss loss;
  EXPECT_THROW(loss.value(Vector::Zero(2), Vector::Zero(3)), Error);
}

}  // namespace
}  // namespace physgrad
