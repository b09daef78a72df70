#include <gtest/gtest.h>

#include <string>

#include "physgrad/error.hpp"
#include "physgrad/threads.hpp"

TEST(BlasThreads, SetAndReadBackWhenTheBlasSupportsIt) {
  EXPECT_THROW(physgrad::set_blas_threads(0), physgrad::Error);
  if (!physgrad::set_blas_threads(2)) GTEST_SKIP() << "the BLAS in use has no thread control";
  EXPECT_EQ(physgrad::blas_threads(), 2);
  EXPECT_TRUE(physgrad::set_blas_threads(1));
  EXPECT_EQ(physgrad::blas_threads(), 1);
}

// The build links OpenBLAS, which names its kernel set; a note, when there is one, names that
// set and the variable that overrides it.
TEST(BlasCore, NamesTheKernelsAndANoteSaysHowToOverrideThem) {
  const std::string core = physgrad::blas_core();
  EXPECT_FALSE(core.empty());
  const std::string note = physgrad::blas_core_note();
  if (note.empty()) return;
  EXPECT_NE(note.find(core), std::string::npos) << note;
  EXPECT_NE(note.find("OPENBLAS_CORETYPE="), std::string::npos) << note;
}

TEST(JacobianThreads, SetAndReadBack) {
  EXPECT_EQ(physgrad::jacobian_threads(), 1);  // the default
  EXPECT_THROW(physgrad::set_jacobian_threads(0), physgrad::Error);
  physgrad::set_jacobian_threads(3);
  EXPECT_EQ(physgrad::jacobian_threads(), 3);
  physgrad::set_jacobian_threads(1);
  EXPECT_EQ(physgrad::jacobian_threads(), 1);
}
