// Mlp and activations: forward against hand computation, the flat parameter layout, backward
// and per-sample gradients against finite differences, initialisation, and shape errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/nn/activation.hpp"
#include "physgrad/nn/mlp.hpp"

namespace physgrad {
namespace {

constexpr Activation kAllActivations[] = {Activation::kTanh, Activation::kRelu,
                                          Activation::kSigmoid, Activation::kSoftplus,
                                          Activation::kIdentity};

// Entries uniform in [−1, 1), reproducible from the seed.
Matrix uniform(Index rows, Index cols, std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  Matrix m(rows, cols);
  for (double& v : m.reshaped()) v = 2 * static_cast<double>(engine() >> 11) * 0x1p-53 - 1;
  return m;
}

// max |a − b| / max |b|.
double relative_error(const Matrix& a, const Matrix& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

Eigen::ArrayXXd apply(Activation activation, const Eigen::ArrayXXd& z) {
  Eigen::ArrayXXd out(z.rows(), z.cols());
  physgrad::apply(activation, z, out);
  return out;
}

Eigen::ArrayXXd derivative(Activation activation, const Eigen::ArrayXXd& z) {
  Eigen::ArrayXXd out(z.rows(), z.cols());
  physgrad::derivative(activation, z, out);
  return out;
}

// The smallest |z_l| over all layers and samples, recomputed from the weight views.
double min_abs_preactivation(const Mlp& net, const Matrix& x) {
  double smallest = std::numeric_limits<double>::infinity();
  Matrix a = x;
  for (Index l = 0; l < net.num_layers(); ++l) {
    const Matrix z = (net.weight(l) * a).colwise() + net.bias(l);
    smallest = std::min(smallest, z.cwiseAbs().minCoeff());
    a = apply(l + 1 == net.num_layers() ? net.output_activation() : net.hidden_activation(),
              z.array())
            .matrix();
  }
  return smallest;
}

// θ ↦ vec(f(x; θ)), samples one after another (row b·m + k is output k of sample b).
Vector outputs_of_parameters(const Mlp& net, const Matrix& x, const Vector& theta) {
  Mlp copy = net;
  copy.set_parameters(theta);
  return copy.forward(x).reshaped();
}

// A 3→5→4→2 net with random θ and a batch of 6 inputs, with every pre-activation at least
// 1e-3 away from 0 (so relu's kink stays out of reach of the finite differences).
struct Problem {
  Mlp net;
  Matrix x;
  Matrix gy;
};

Problem random_problem(Activation hidden, Activation output) {
  for (std::uint64_t seed = 1; seed < 100; ++seed) {
    Problem s{Mlp({3, 5, 4, 2}, hidden, output), uniform(3, 6, seed + 1000),
            uniform(2, 6, seed + 2000)};
    s.net.set_parameters(uniform(s.net.num_parameters(), 1, seed));
    if (min_abs_preactivation(s.net, s.x) >= 1e-3) return s;
  }
  throw Error("no seed keeps the pre-activations away from 0");
}

TEST(MlpForward, TinyTanhNetMatchesHandComputation) {
  Mlp net({2, 2, 1});
  // θ = [W_0 column-major, b_0, W_1, b_1] with W_0 = [[0.5, −1], [2, 0.25]], W_1 = [1.5, −0.5].
  net.set_parameters(Vector{{0.5, 2.0, -1.0, 0.25, 0.1, -0.2, 1.5, -0.5, 0.3}});
  const Matrix x{{0.4, 1.0}, {-0.6, 2.0}};
  Matrix expected(1, 2);
  for (Index b = 0; b < 2; ++b) {
    const double h0 = std::tanh(0.5 * x(0, b) - 1.0 * x(1, b) + 0.1);
    const double h1 = std::tanh(2.0 * x(0, b) + 0.25 * x(1, b) - 0.2);
    expected(0, b) = 1.5 * h0 - 0.5 * h1 + 0.3;
  }
  EXPECT_LT((net.forward(x) - expected).cwiseAbs().maxCoeff(), 1e-15);
  MlpCache cache;
  EXPECT_LT((net.forward(x, cache) - expected).cwiseAbs().maxCoeff(), 1e-15);
  ASSERT_EQ(cache.activations.size(), 3u);
  EXPECT_EQ(cache.activations[0], x);
  EXPECT_NEAR(cache.activations[1](1, 0), std::tanh(2.0 * 0.4 + 0.25 * -0.6 - 0.2), 1e-15);
  EXPECT_NEAR(cache.derivatives[0](1, 0),
              1 - std::pow(std::tanh(2.0 * 0.4 + 0.25 * -0.6 - 0.2), 2), 1e-15);
}

TEST(MlpForward, CacheStorageIsReusedForTheSameShape) {
  Problem s = random_problem(Activation::kTanh, Activation::kSigmoid);
  MlpCache cache;
  s.net.forward(s.x, cache);
  std::vector<const double*> storage;
  for (const Matrix& m : cache.activations) storage.push_back(m.data());
  for (const Matrix& m : cache.derivatives) storage.push_back(m.data());
  const Matrix x2 = uniform(3, 6, 77);
  EXPECT_EQ(s.net.forward(x2, cache), s.net.forward(x2));
  std::size_t i = 0;
  for (const Matrix& m : cache.activations) EXPECT_EQ(m.data(), storage[i++]);
  for (const Matrix& m : cache.derivatives) EXPECT_EQ(m.data(), storage[i++]);
}

TEST(MlpLayout, ViewsAliasTheFlatParameterVector) {
  Mlp net({3, 4, 2});
  EXPECT_EQ(net.num_layers(), 2);
  EXPECT_EQ(net.input_dim(), 3);
  EXPECT_EQ(net.output_dim(), 2);
  EXPECT_EQ(net.num_parameters(), 3 * 4 + 4 + 4 * 2 + 2);
  EXPECT_EQ(net.widths(), (std::vector<Index>{3, 4, 2}));
  EXPECT_EQ(net.hidden_activation(), Activation::kTanh);
  EXPECT_EQ(net.output_activation(), Activation::kIdentity);

  net.weight(1)(1, 2) = 7.0;  // layer 1 starts at 16; column 2 of a 2-row W starts at +4
  net.bias(0)(3) = -5.0;      // b_0 follows the 12 entries of W_0
  EXPECT_EQ(net.parameters()(16 + 2 * 2 + 1), 7.0);
  EXPECT_EQ(net.parameters()(12 + 3), -5.0);
  EXPECT_EQ(net.parameters().cwiseAbs().sum(), 12.0);

  net.parameters()(24) = 3.0;  // b_1(0)
  const Mlp& const_net = net;
  EXPECT_EQ(const_net.bias(1)(0), 3.0);
  EXPECT_EQ(const_net.weight(1).rows(), 2);
  EXPECT_EQ(const_net.weight(1).cols(), 4);

  // A view taken before set_parameters sees the new values.
  const Eigen::Map<Matrix> w0 = net.weight(0);
  const Vector theta = uniform(net.num_parameters(), 1, 5);
  net.set_parameters(theta);
  EXPECT_EQ(w0(2, 1), theta(1 * 4 + 2));
  EXPECT_THROW(net.weight(2), Error);
  EXPECT_THROW(net.bias(-1), Error);
}

TEST(MlpBackward, GradientsMatchFiniteDifferencesForEveryActivation) {
  for (const Activation activation : kAllActivations) {
    // The activation once in the hidden layers and once at the output.
    for (const auto& [hidden, output] : {std::pair{activation, Activation::kIdentity},
                                         std::pair{Activation::kTanh, activation}}) {
      SCOPED_TRACE(to_string(hidden) + " / " + to_string(output));
      const Problem s = random_problem(hidden, output);
      MlpCache cache;
      s.net.forward(s.x, cache);
      Matrix gx;
      const Vector grad = s.net.backward(cache, s.gy, &gx);
      ASSERT_GT(grad.norm(), 0.1);

      const auto objective_of_theta = [&](const Vector& theta) {
        return Vector::Constant(1, s.gy.reshaped().dot(outputs_of_parameters(s.net, s.x, theta)));
      };
      const Matrix fd = finite_difference_jacobian(objective_of_theta, s.net.parameters());
      EXPECT_LT(relative_error(grad.transpose(), fd), 1e-7);

      const auto objective_of_x = [&](const Vector& x) {
        const Matrix y = s.net.forward(x.reshaped(3, 6));
        return Vector::Constant(1, s.gy.cwiseProduct(y).sum());
      };
      const Matrix fd_x = finite_difference_jacobian(objective_of_x, s.x.reshaped());
      ASSERT_EQ(gx.rows(), 3);
      ASSERT_EQ(gx.cols(), 6);
      EXPECT_LT(relative_error(gx.reshaped().transpose(), fd_x), 1e-7);
    }
  }
}

TEST(MlpPerSampleGradients, RowsAreSingleSampleGradientsAndSumToTheBatchGradient) {
  const Problem s = random_problem(Activation::kSoftplus, Activation::kSigmoid);
  MlpCache cache;
  s.net.forward(s.x, cache);
  const Matrix rows = s.net.per_sample_gradients(cache, s.gy);
  ASSERT_EQ(rows.rows(), 6);
  ASSERT_EQ(rows.cols(), s.net.num_parameters());
  for (Index b = 0; b < 6; ++b) {
    MlpCache single;
    s.net.forward(s.x.col(b), single);
    const Vector alone = s.net.backward(single, s.gy.col(b));
    EXPECT_LT(relative_error(rows.row(b), alone.transpose()), 1e-12) << "sample " << b;

    const auto objective = [&](const Vector& theta) {
      return Vector::Constant(
          1, s.gy.col(b).dot(outputs_of_parameters(s.net, s.x.col(b), theta)));
    };
    const Matrix fd = finite_difference_jacobian(objective, s.net.parameters());
    EXPECT_LT(relative_error(rows.row(b), fd), 1e-7) << "sample " << b;
  }
  EXPECT_LT(relative_error(rows.colwise().sum(), s.net.backward(cache, s.gy).transpose()),
            1e-12);
}

TEST(MlpPerSampleGradients, StackedJacobianMatchesFiniteDifferences) {
  const Problem s = random_problem(Activation::kTanh, Activation::kSoftplus);
  const Index m = s.net.output_dim();
  const Index batch = s.x.cols();
  const Index p = s.net.num_parameters();
  MlpCache cache;
  s.net.forward(s.x, cache);
  Matrix stacked(batch * m, p);   // from the returning overload, rows placed one by one
  Matrix in_place(batch * m, p);  // written directly into every m-th row
  for (Index k = 0; k < m; ++k) {
    Matrix gy = Matrix::Zero(m, batch);
    gy.row(k).setOnes();
    const Matrix rows = s.net.per_sample_gradients(cache, gy);
    for (Index b = 0; b < batch; ++b) stacked.row(b * m + k) = rows.row(b);
    using Stride = Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>;
    const Eigen::Map<Matrix, 0, Stride> every_mth_row(in_place.data() + k, batch, p,
                                                      Stride(batch * m, m));
    s.net.per_sample_gradients(cache, gy, every_mth_row);
  }
  const auto f = [&](const Vector& theta) { return outputs_of_parameters(s.net, s.x, theta); };
  const Matrix fd = finite_difference_jacobian(f, s.net.parameters());
  EXPECT_LT(relative_error(stacked, fd), 1e-7);
  EXPECT_EQ(in_place, stacked);
}

TEST(MlpInitialize, IsSeededAndRespectsTheLimits) {
  Mlp net({400, 300, 20});
  net.initialize(11);
  const Vector first = net.parameters();
  net.parameters().setConstant(1.0);
  net.initialize(11);
  EXPECT_EQ(net.parameters(), first);
  net.initialize(12);
  EXPECT_NE(net.parameters(), first);

  // The first weight is the documented mapping of the engine's first draw.
  std::mt19937_64 engine(12);
  const double u = static_cast<double>(engine() >> 11) * 0x1p-53;
  EXPECT_EQ(net.weight(0)(0, 0), std::sqrt(6.0 / 700) * (2 * u - 1));

  for (const Init init : {Init::kGlorotUniform, Init::kHeUniform}) {
    SCOPED_TRACE(to_string(init));
    EXPECT_EQ(parse_init(to_string(init)), init);
    net.parameters().setConstant(1.0);
    net.initialize(3, init);
    for (Index l = 0; l < net.num_layers(); ++l) {
      const double fan_in = static_cast<double>(net.widths()[l]);
      const double fan_out = static_cast<double>(net.widths()[l + 1]);
      const double limit =
          std::sqrt(6.0 / (init == Init::kGlorotUniform ? fan_in + fan_out : fan_in));
      EXPECT_LE(net.weight(l).cwiseAbs().maxCoeff(), limit);
      EXPECT_GT(net.weight(l).cwiseAbs().maxCoeff(), 0.9 * limit);
      EXPECT_TRUE(net.bias(l).isZero(0.0));
    }
    const Vector w = net.weight(0).reshaped();  // 120 000 weights
    const double mean = w.mean();
    const double variance = (w.array() - mean).square().mean();
    const double limit = std::sqrt(6.0 / (init == Init::kGlorotUniform ? 700.0 : 400.0));
    EXPECT_NEAR(variance, limit * limit / 3, 0.1 * limit * limit / 3);
  }
}

TEST(MlpActivation, DerivativesMatchFiniteDifferencesAndTheCombinedCall) {
  const Eigen::ArrayXXd z{{-3.0, -0.7, -0.01, 0.02, 0.5, 2.5}};
  const double h = 1e-6;
  for (const Activation activation : kAllActivations) {
    SCOPED_TRACE(to_string(activation));
    EXPECT_EQ(parse_activation(to_string(activation)), activation);
    const Eigen::ArrayXXd fd = (apply(activation, z + h) - apply(activation, z - h)) / (2 * h);
    EXPECT_LT((derivative(activation, z) - fd).abs().maxCoeff(), 1e-8);
    Eigen::ArrayXXd value = z;
    Eigen::ArrayXXd slope(z.rows(), z.cols());
    apply_with_derivative(activation, value, slope);
    EXPECT_TRUE((value == apply(activation, z)).all());
    EXPECT_TRUE((slope == derivative(activation, z)).all());
  }
  EXPECT_EQ(derivative(Activation::kRelu, Eigen::ArrayXXd::Zero(1, 1))(0, 0), 0.0);
}

TEST(MlpActivation, SoftplusAndSigmoidStayAccurateForLargeArguments) {
  const Eigen::ArrayXXd z{{-800.0, -30.0, 0.0, 30.0, 800.0}};
  const Eigen::ArrayXXd softplus = apply(Activation::kSoftplus, z);
  const Eigen::ArrayXXd slope = derivative(Activation::kSoftplus, z);
  const Eigen::ArrayXXd sigmoid_slope = derivative(Activation::kSigmoid, z);
  ASSERT_TRUE(softplus.allFinite());
  ASSERT_TRUE(slope.allFinite());
  ASSERT_TRUE(sigmoid_slope.allFinite());
  const double e = std::exp(-30.0);  // log(1 + e^−30) ≈ e^−30 is lost by a naive log(1 + e^z)
  EXPECT_EQ(softplus(0), 0.0);
  EXPECT_NEAR(softplus(1), std::log1p(e), 1e-15 * e);
  EXPECT_NEAR(softplus(2), std::log(2.0), 1e-16);
  EXPECT_DOUBLE_EQ(softplus(3), 30.0 + std::log1p(e));
  EXPECT_EQ(softplus(4), 800.0);
  EXPECT_EQ(slope(0), 0.0);
  EXPECT_NEAR(slope(1), e / (1 + e), 1e-15 * e);
  EXPECT_EQ(slope(2), 0.5);
  EXPECT_EQ(slope(4), 1.0);
  EXPECT_NEAR(sigmoid_slope(3), e / ((1 + e) * (1 + e)), 1e-15 * e);
  EXPECT_EQ(sigmoid_slope(4), 0.0);
}

TEST(MlpErrors, RejectsBadShapesAndNames) {
  EXPECT_THROW(Mlp({3}), Error);
  EXPECT_THROW(Mlp({3, 0, 2}), Error);
  Mlp net({3, 4, 2});
  EXPECT_THROW(net.forward(Matrix::Zero(2, 5)), Error);
  MlpCache cache;
  EXPECT_THROW(net.forward(Matrix::Zero(4, 5), cache), Error);
  EXPECT_THROW(net.backward(cache, Matrix::Zero(2, 5)), Error);  // cache never filled
  net.forward(Matrix::Zero(3, 5), cache);
  EXPECT_NO_THROW(net.backward(cache, Matrix::Zero(2, 5)));
  EXPECT_THROW(net.backward(cache, Matrix::Zero(3, 5)), Error);
  EXPECT_THROW(net.backward(cache, Matrix::Zero(2, 4)), Error);
  EXPECT_THROW(net.per_sample_gradients(cache, Matrix::Zero(2, 4)), Error);
  Matrix out(5, net.num_parameters() - 1);
  EXPECT_THROW(net.per_sample_gradients(cache, Matrix::Zero(2, 5), out), Error);
  EXPECT_THROW(Mlp({3, 5, 2}).backward(cache, Matrix::Zero(2, 5)), Error);  // foreign cache
  EXPECT_THROW(net.set_parameters(Vector::Zero(net.num_parameters() + 1)), Error);
  net.parameters().resize(3);
  EXPECT_THROW(net.forward(Matrix::Zero(3, 1)), Error);
  try {
    parse_activation("swish");
    ADD_FAILURE() << "parse_activation accepted 'swish'";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("swish"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("softplus"), std::string::npos);
  }
  EXPECT_THROW(parse_init("xavier"), Error);
}

}  // namespace
}  // namespace physgrad
