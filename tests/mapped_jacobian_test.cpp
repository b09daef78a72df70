// MappedJacobian: a row-major J read in place as Jᵀ gives the products of the formed J, and the
// HIG step on it is the step on the formed matrix.
#include <gtest/gtest.h>

#include <memory>

#include "physgrad/error.hpp"
#include "physgrad/learn/hig.hpp"
#include "physgrad/learn/mapped_jacobian.hpp"

namespace physgrad {
namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct Buffer {
  Index batch, outputs, cols;
  RowMajor j;  // the caller's memory, (B·m) × P row-major
  Buffer(Index b, Index m, Index p)
      : batch(b), outputs(m), cols(p), j(RowMajor::Random(b * m, p)) {}
  MappedJacobian mapped() const { return MappedJacobian(j.data(), batch, outputs, cols); }
  Matrix formed() const { return j; }
};

TEST(MappedJacobian, ReadsTheGivenMemoryAsJ) {
  const Buffer wide(3, 2, 11), tall(4, 3, 5);
  for (const Buffer* b : {&wide, &tall}) {
    const MappedJacobian j = b->mapped();
    const Matrix formed = b->formed();
    EXPECT_EQ(j.data(), b->j.data());  // not copied
    EXPECT_EQ(j.rows(), formed.rows());
    EXPECT_EQ(j.cols(), formed.cols());
    EXPECT_EQ(j.materialize(), formed);
    const Matrix gram = formed * formed.transpose();
    EXPECT_LT((Matrix(j.gram().triangularView<Eigen::Lower>()) -
               Matrix(gram.triangularView<Eigen::Lower>())).cwiseAbs().maxCoeff(), 1e-12);
    const Vector c = Vector::Random(formed.rows());
    EXPECT_LT((j.apply_transpose(c) - formed.transpose() * c).cwiseAbs().maxCoeff(), 1e-12);
    const StackedJacobian::Normal normal = j.normal(c);
    const Matrix jtj = formed.transpose() * formed;
    EXPECT_LT((Matrix(normal.matrix.triangularView<Eigen::Lower>()) -
               Matrix(jtj.triangularView<Eigen::Lower>())).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((normal.rhs - formed.transpose() * c).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(MappedJacobian, TheHigStepIsTheStepOnTheFormedJacobian) {
  const Buffer b(6, 2, 40);
  BatchState state;
  state.jacobian = std::make_shared<MappedJacobian>(b.mapped());
  state.loss_gradient_y = Vector::Random(12);
  for (const double kappa : {0.5, 1.0}) {
    HigUpdate update({.lr = 0.5, .cut = {.kappa = kappa, .rcond = 1e-6}});
    const Vector expected =
        -0.5 * power_pinv_apply(b.formed(), state.loss_gradient_y,
                                {.cut = {.kappa = kappa, .rcond = 1e-6}, .backend = PinvBackend::kSvd});
    const Vector step = update.step(state).delta;
    EXPECT_LT((step - expected).norm(), 1e-10 * expected.norm()) << kappa;
  }
}

TEST(MappedJacobian, RefusesNegativeSizesAndMissingData) {
  EXPECT_THROW(MappedJacobian(nullptr, 2, 1, 3), Error);
  const double x = 0;
  EXPECT_THROW(MappedJacobian(&x, -1, 1, 1), Error);
  EXPECT_NO_THROW(MappedJacobian(nullptr, 0, 1, 3));
}

}  // namespace
}  // namespace physgrad
