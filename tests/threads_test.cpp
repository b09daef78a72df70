#include <gtest/gtest.h>

#include "physgrad/error.hpp"
#include "physgrad/threads.hpp"

TEST(BlasThreads, SetAndReadBackWhenTheBlasSupportsIt) {
  EXPECT_THROW(physgrad::set_blas_threads(0), physgrad::Error);
  if (!physgrad::set_blas_threads(2)) GTEST_SKIP() << "the BLAS in use has no thread control";
  EXPECT_EQ(physgrad::blas_threads(), 2);
  EXPECT_TRUE(physgrad::set_blas_threads(1));
  EXPECT_EQ(physgrad::blas_threads(), 1);
}

TEST(JacobianThreads, SetAndReadBack) {
  EXPECT_EQ(physgrad::jacobian_threads(), 1);  // the default
  EXPECT_THROW(physgrad::set_jacobian_threads(0), physgrad::Error);
  physgrad::set_jacobian_threads(3);
  EXPECT_EQ(physgrad::jacobian_threads(), 3);
  physgrad::set_jacobian_threads(1);
  EXPECT_EQ(physgrad::jacobian_threads(), 1);
}
