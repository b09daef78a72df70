// ConvNetwork: backward, per-sample gradients and jvp against central finite differences of
// forward() for conv stacks and small U-nets, phiml's parameter count, errors, and periodic
// translation equivariance.
#include "physgrad/nn/conv_net.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "physgrad/error.hpp"

namespace physgrad {
namespace {

Matrix conv_uniform(Index rows, Index cols, std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  Matrix m(rows, cols);
  for (double& v : m.reshaped()) v = 2 * static_cast<double>(engine() >> 11) * 0x1p-53 - 1;
  return m;
}

// Up to `count` parameter indices spread over θ (all when θ is small).
std::vector<Index> conv_probe_indices(Index size, Index count) {
  std::vector<Index> out;
  const Index step = std::max<Index>(1, size / count);
  for (Index k = 0; k < size; k += step) out.push_back(k);
  out.push_back(size - 1);
  return out;
}

// Σ gy ⊙ f(x) with θ[k] moved by ±h, central difference.
double conv_fd_entry(ConvNetwork& net, const Matrix& x, const Matrix& gy, Index k) {
  constexpr double h = 1e-6;
  const double keep = net.parameters()[k];
  net.parameters()[k] = keep + h;
  const double plus = (gy.array() * net.forward(x).array()).sum();
  net.parameters()[k] = keep - h;
  const double minus = (gy.array() * net.forward(x).array()).sum();
  net.parameters()[k] = keep;
  return (plus - minus) / (2 * h);
}

void expect_close(double got, double want, double scale, const std::string& what) {
  EXPECT_NEAR(got, want, 1e-6 * (1.0 + scale)) << what;
}

// Every derivative member of `net` against finite differences of forward(); `per_sample` also
// checks per_sample_gradients and jvp.
void check_derivatives(ConvNetwork& net, Index batch, bool per_sample) {
  net.initialize(7);
  const Matrix x = conv_uniform(net.input_dim(), batch, 11);
  const Matrix gy = conv_uniform(net.output_dim(), batch, 13);
  auto cache = net.new_cache();
  net.forward(x, *cache);
  const Vector grad = net.backward(*cache, gy);
  const double scale = grad.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0.0);
  const auto probes = conv_probe_indices(net.num_parameters(), 60);
  for (const Index k : probes) {
    expect_close(grad[k], conv_fd_entry(net, x, gy, k), scale,
                 "backward, θ[" + std::to_string(k) + "]");
  }
  if (!per_sample) return;
  const Matrix rows = net.per_sample_gradients(*cache, gy);
  ASSERT_EQ(rows.rows(), batch);
  for (Index b = 0; b < batch; ++b) {
    for (const Index k : probes) {
      expect_close(rows(b, k), conv_fd_entry(net, x.col(b), gy.col(b), k), scale,
                   "per-sample row " + std::to_string(b) + ", θ[" + std::to_string(k) + "]");
    }
  }
  const Vector v = conv_uniform(net.num_parameters(), 1, 17).col(0);
  const Matrix tangent = net.jvp(*cache, batch, v);
  const Vector theta = net.parameters();
  constexpr double h = 1e-6;
  net.parameters() = theta + h * v;
  const Matrix plus = net.forward(x);
  net.parameters() = theta - h * v;
  const Matrix minus = net.forward(x);
  net.parameters() = theta;
  const Matrix fd = (plus - minus) / (2 * h);
  const double tscale = fd.cwiseAbs().maxCoeff();
  ASSERT_GT(tscale, 0.0);
  EXPECT_LT((tangent - fd).cwiseAbs().maxCoeff(), 1e-6 * (1.0 + tscale));
}

TEST(ConvNetwork, Stack2dZeroPaddingMatchesFiniteDifferences) {
  auto net = ConvNetwork::conv_stack(2, 6, {2, 3, 2}, 3, Activation::kTanh, Padding::kZero);
  EXPECT_EQ(net.input_dim(), 2 * 36);
  EXPECT_EQ(net.num_parameters(), (2 * 9 + 1) * 3 + (3 * 9 + 1) * 2);
  check_derivatives(net, 3, true);
}

TEST(ConvNetwork, Stack2dPeriodicMatchesFiniteDifferences) {
  auto net = ConvNetwork::conv_stack(2, 5, {1, 3, 1}, 3, Activation::kSoftplus, Padding::kPeriodic);
  check_derivatives(net, 3, true);
}

TEST(ConvNetwork, Stack1dMatchesFiniteDifferences) {
  auto net = ConvNetwork::conv_stack(1, 9, {2, 4, 3, 1}, 5, Activation::kTanh, Padding::kZero);
  EXPECT_EQ(net.num_parameters(), (2 * 5 + 1) * 4 + (4 * 5 + 1) * 3 + (3 * 5 + 1) * 1);
  check_derivatives(net, 3, true);
}

UNetOptions small_unet() {
  UNetOptions o;
  o.n = 8;
  o.levels = 3;
  o.filters = 4;
  o.in_channels = 2;
  o.out_channels = 1;
  o.activation = Activation::kTanh;
  return o;
}

TEST(ConvNetwork, UNetMaxPoolBilinearMatchesFiniteDifferences) {
  auto net = ConvNetwork::unet(small_unet());
  check_derivatives(net, 2, true);
}

TEST(ConvNetwork, UNetStridedNearestPeriodicMatchesFiniteDifferences) {
  UNetOptions o = small_unet();
  o.down = Downsample::kStrided;
  o.up = Upsample::kNearest;
  o.padding = Padding::kPeriodic;
  auto net = ConvNetwork::unet(o);
  check_derivatives(net, 2, true);
}

TEST(ConvNetwork, UNet1dMatchesFiniteDifferences) {
  UNetOptions o = small_unet();
  o.dims = 1;
  o.n = 16;
  auto net = ConvNetwork::unet(o);
  check_derivatives(net, 2, true);
}

TEST(ConvNetwork, UNetBatchNormBackwardMatchesFiniteDifferences) {
  UNetOptions o = small_unet();
  o.batch_norm = true;
  auto net = ConvNetwork::unet(o);
  check_derivatives(net, 3, false);
  o.down = Downsample::kStrided;
  o.up = Upsample::kNearest;
  auto strided = ConvNetwork::unet(o);
  check_derivatives(strided, 3, false);
}

TEST(ConvNetwork, UNetParameterCountMatchesPhiml) {
  UNetOptions o;
  o.batch_norm = true;
  EXPECT_EQ(ConvNetwork::unet(o).num_parameters(), 37697);
  o.batch_norm = false;  // 14 batch norms of 16 channels, each γ and β
  EXPECT_EQ(ConvNetwork::unet(o).num_parameters(), 37697 - 14 * 32);
  EXPECT_EQ(ConvNetwork::unet(o).describe()["parameters"], 37697 - 14 * 32);
}

std::string conv_error_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(ConvNetwork, BadOptionsNameTheValue) {
  UNetOptions o;
  o.n = 12;  // 2^3 = 8 does not divide 12
  EXPECT_NE(conv_error_of([&] { ConvNetwork::unet(o); }).find("n 12"), std::string::npos);
  o = UNetOptions{};
  o.levels = 0;
  EXPECT_NE(conv_error_of([&] { ConvNetwork::unet(o); }).find("levels 0"), std::string::npos);
  o = UNetOptions{};
  o.dims = 3;
  EXPECT_NE(conv_error_of([&] { ConvNetwork::unet(o); }).find("dims 3"), std::string::npos);
  EXPECT_NE(conv_error_of([] {
              ConvNetwork::conv_stack(2, 4, {1, 1}, 2);
            }).find("kernel 2"),
            std::string::npos);
  auto net = ConvNetwork::conv_stack(2, 4, {1, 2});
  const std::string wrong = conv_error_of([&] { net.forward(Matrix::Zero(15, 2)); });
  EXPECT_NE(wrong.find("15x2"), std::string::npos) << wrong;
  EXPECT_EQ(wrong.find('\n'), std::string::npos);
}

TEST(ConvNetwork, BatchNormRefusesPerSampleMembers) {
  UNetOptions o = small_unet();
  o.batch_norm = true;
  auto net = ConvNetwork::unet(o);
  net.initialize(1);
  const Matrix x = conv_uniform(net.input_dim(), 2, 3);
  const Matrix gy = conv_uniform(net.output_dim(), 2, 4);
  auto cache = net.new_cache();
  net.forward(x, *cache);
  const std::vector<std::function<void()>> calls = {
      [&] { net.per_sample_gradients(*cache, gy); },
      [&] { net.jvp(*cache, 2, Vector::Zero(net.num_parameters())); },
      [&] { net.per_sample_gram(*cache, {gy}); }, [&] { net.dense_layer_factors(*cache, {gy}); }};
  for (const auto& call : calls) {
    const std::string message = conv_error_of(call);
    EXPECT_NE(message.find("batch norm couples the samples"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos);
  }
  EXPECT_EQ(net.backward(*cache, gy).size(), net.num_parameters());
}

// Shifting the input field by (di, dj) cells around the torus shifts the output the same way.
TEST(ConvNetwork, PeriodicStackIsTranslationEquivariant) {
  const Index n = 6;
  auto net = ConvNetwork::conv_stack(2, n, {2, 3, 2}, 3, Activation::kTanh, Padding::kPeriodic);
  net.initialize(5);
  const Matrix x = conv_uniform(net.input_dim(), 1, 9);
  const auto shift = [n](const Matrix& field, Index channels) {
    Matrix out(field.rows(), 1);
    for (Index c = 0; c < channels; ++c) {
      for (Index j = 0; j < n; ++j) {
        for (Index i = 0; i < n; ++i) {
          out(c * n * n + (i + 2) % n + n * ((j + 1) % n), 0) = field(c * n * n + i + n * j, 0);
        }
      }
    }
    return out;
  };
  const Matrix y = net.forward(x);
  const Matrix y_shifted = net.forward(shift(x, 2));
  EXPECT_LT((y_shifted - shift(y, 2)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT((y_shifted - y).cwiseAbs().maxCoeff(), 1e-3);  // the shift is visible
  auto zero = ConvNetwork::conv_stack(2, n, {2, 3, 2}, 3, Activation::kTanh, Padding::kZero);
  zero.parameters() = net.parameters();
  EXPECT_GT((zero.forward(shift(x, 2)) - shift(zero.forward(x), 2)).cwiseAbs().maxCoeff(), 1e-3);
}

// Two conv threads give the same forward and per-sample rows and the same summed gradient up to
// round-off.
TEST(ConvNetwork, ThreadCountChangesOnlyRoundOff) {
  auto net = ConvNetwork::unet(small_unet());
  net.initialize(3);
  const Matrix x = conv_uniform(net.input_dim(), 5, 1);
  const Matrix gy = conv_uniform(net.output_dim(), 5, 2);
  const auto run = [&](int threads) {
    set_conv_threads(threads);
    auto cache = net.new_cache();
    Matrix y = net.forward(x, *cache);
    Vector grad = net.backward(*cache, gy);
    Matrix rows = net.per_sample_gradients(*cache, gy);
    Matrix tangent = net.jvp(*cache, 5, conv_uniform(net.num_parameters(), 1, 4).col(0));
    set_conv_threads(1);
    return std::make_tuple(y, grad, rows, tangent);
  };
  const auto [y1, g1, r1, t1] = run(1);
  const auto [y2, g2, r2, t2] = run(2);
  EXPECT_EQ(y1, y2);
  EXPECT_EQ(r1, r2);
  EXPECT_EQ(t1, t2);
  EXPECT_LT((g1 - g2).cwiseAbs().maxCoeff(), 1e-12 * g1.cwiseAbs().maxCoeff());
  EXPECT_EQ(std::get<1>(run(2)), g2);  // deterministic for a given count
  EXPECT_THROW(set_conv_threads(0), Error);
}

}  // namespace
}  // namespace physgrad
