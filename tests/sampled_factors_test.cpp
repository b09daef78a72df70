// kfac / kfac-hig with sampled output directions (option samples = K): with K = m the factors and
// the step are the exact ones; the mean of S over many draws approaches the exact S within the
// standard error of that many draws; bad values of K are named; a checkpoint resumes the draws.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/io/serialize.hpp"
#include "physgrad/nn/conv_net.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/physics/heat_diffusion.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad {
namespace {

Matrix sampled_test_uniform(Index rows, Index cols, std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  Matrix m(rows, cols);
  for (double& v : m.reshaped()) v = 2 * static_cast<double>(engine() >> 11) * 0x1p-53 - 1;
  return m;
}

double sampled_test_difference(const Matrix& a, const Matrix& b) {
  return (a - b).norm() / b.norm();
}

// A tanh network (3 → 8 → 6) in front of 1-D heat diffusion on 6 cells (m = 6 outputs, P not
// the identity), or a U-net (8×8 cells, 2 levels, 4 filters) in front of 2-D heat (m = 64).
struct SampledProblem {
  HeatDiffusion physics;
  L2Loss loss{1.0};
  LearningProblem problem{&physics, &loss};
  std::unique_ptr<Network> network;
  Dataset data;

  SampledProblem(bool conv, Index batch)
      : physics(HeatConfig{.n = conv ? 8 : 6, .dims = conv ? 2 : 1, .amount = 0.02}) {
    const Index m = physics.output_dim();
    if (conv) {
      UNetOptions o;
      o.n = 8;
      o.levels = 2;
      o.filters = 4;
      auto net = std::make_unique<ConvNetwork>(ConvNetwork::unet(o));
      net->initialize(4);
      network = std::move(net);
    } else {
      auto net = std::make_unique<Mlp>(std::vector<Index>{3, 8, 6}, Activation::kTanh);
      net->initialize(3);
      network = std::move(net);
    }
    data.inputs = sampled_test_uniform(network->input_dim(), batch, 5);
    data.targets = 0.5 * sampled_test_uniform(m, batch, 6);
  }
  Index outputs() const { return physics.output_dim(); }
  BatchState evaluate(UpdateNeed need, NetworkCache& cache) const {
    return evaluate_batch(*network, problem, data, need, cache);
  }
};

// Each layer's factor `name` ("input_factor" or "cotangent_factor") in the rule's state.
std::vector<Vector> saved_factors(const KroneckerHigUpdate& rule, const char* name) {
  std::vector<Vector> out;
  for (const nlohmann::json& layer : rule.state().at("layers")) {
    out.push_back(vector_from_json(layer, name));
  }
  return out;
}

TEST(SampledFactors, AllOutputsAsDirectionsGiveTheExactFactorsAndStep) {
  for (const bool conv : {false, true}) {
    const SampledProblem s(conv, 3);
    auto cache = s.network->new_cache();
    for (const double kappa : {0.5, 1.0}) {
      KroneckerHigUpdate exact({.lr = 0.5, .cut = KroneckerHigOptions{}.cut.with_kappa(kappa)});
      KroneckerHigUpdate sampled(
          {.lr = 0.5,
           .cut = KroneckerHigOptions{}.cut.with_kappa(kappa),
           .samples = static_cast<int>(s.outputs())});
      ASSERT_EQ(sampled.need(), UpdateNeed::kWeightedFactors);
      const Vector expected = exact.step(s.evaluate(exact.need(), *cache)).delta;
      const Vector got = sampled.step(s.evaluate(sampled.need(), *cache)).delta;
      EXPECT_LT(sampled_test_difference(got, expected), 1e-10) << "conv " << conv;
      for (const char* name : {"input_factor", "cotangent_factor"}) {
        const std::vector<Vector> a = saved_factors(sampled, name), b = saved_factors(exact, name);
        ASSERT_EQ(a.size(), b.size());
        for (std::size_t l = 0; l < a.size(); ++l) {
          EXPECT_LT(sampled_test_difference(a[l], b[l]), 1e-10) << name << " " << l;
        }
      }
    }
  }
}

// N draws of S (K = 2 of m = 6 directions per sample, the factors replaced at every refresh:
// factor_decay 0) on one batch. Each entry's mean has standard error σ/√N, σ estimated from the
// draws; the mean is within 5 standard errors of the exact entry (a normal deviate beyond 5 has
// probability 6e-7, over the ~100 entries 6e-5), while a single draw is not near it.
TEST(SampledFactors, TheMeanOverDrawsApproachesTheExactCotangentFactor) {
  const SampledProblem s(false, 3);
  auto cache = s.network->new_cache();
  KroneckerHigUpdate exact({.refresh = 1});
  exact.step(s.evaluate(exact.need(), *cache));
  const std::vector<Vector> exact_s = saved_factors(exact, "cotangent_factor");
  const std::vector<Vector> exact_a = saved_factors(exact, "input_factor");

  KroneckerHigUpdate sampled({.refresh = 1, .factor_decay = 0, .samples = 2});
  const BatchState state = s.evaluate(sampled.need(), *cache);
  constexpr int kDraws = 4000;
  std::vector<Vector> sum, squares, first;
  for (int d = 0; d < kDraws; ++d) {
    sampled.step(state);  // θ is not moved: every draw is of the same batch
    const std::vector<Vector> draw = saved_factors(sampled, "cotangent_factor");
    if (d == 0) {
      first = draw;
      for (const Vector& v : draw) {
        sum.push_back(Vector::Zero(v.size()));
        squares.push_back(Vector::Zero(v.size()));
      }
      // A is not sampled.
      const std::vector<Vector> a = saved_factors(sampled, "input_factor");
      for (std::size_t l = 0; l < a.size(); ++l) {
        EXPECT_LT(sampled_test_difference(a[l], exact_a[l]), 1e-13);
      }
    }
    for (std::size_t l = 0; l < draw.size(); ++l) {
      sum[l] += draw[l];
      squares[l] += draw[l].cwiseAbs2();
    }
  }
  const double n = kDraws;
  for (std::size_t l = 0; l < sum.size(); ++l) {
    const Vector mean = sum[l] / n;
    const Vector variance = ((squares[l] / n - mean.cwiseAbs2()) * n / (n - 1)).cwiseMax(0.0);
    const Vector tolerance = 5 * (variance / n).cwiseSqrt();
    for (Index e = 0; e < mean.size(); ++e) {
      EXPECT_LE(std::abs(mean(e) - exact_s[l](e)), tolerance(e) + 1e-12 * exact_s[l].norm())
          << "layer " << l << " entry " << e;
    }
    // The bound is tighter than one draw's error, so the test sees the averaging.
    EXPECT_GT((first[l] - exact_s[l]).cwiseAbs().maxCoeff(), 10 * tolerance.maxCoeff()) << l;
  }
}

TEST(SampledFactors, BadCountsAreNamed) {
  for (const nlohmann::json& bad : {nlohmann::json(-1), nlohmann::json(2.5)}) {
    try {
      make_learning_update("kfac-hig", {{"samples", bad}});
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("samples"), std::string::npos) << message;
      EXPECT_NE(message.find(bad.dump()), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
  // More directions than the physics has outputs: named at the refresh, nothing changed.
  const SampledProblem s(false, 3);
  auto cache = s.network->new_cache();
  KroneckerHigUpdate rule({.samples = 7});
  try {
    rule.step(s.evaluate(rule.need(), *cache));
    ADD_FAILURE() << "samples 7 of 6 outputs";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("samples 7 exceeds the 6 physics outputs"), std::string::npos)
        << message;
  }
  EXPECT_TRUE(rule.state().is_null());
  // Without samples params() does not list it; with it, kfac and kfac-hig do.
  EXPECT_FALSE(make_learning_update("kfac-hig")->params().contains("samples"));
  EXPECT_EQ(make_learning_update("kfac", {{"samples", 4}})->params().at("samples"), 4);
  // A refresh with samples needs the batch's weighted factors, not the stacked Jacobian alone.
  KroneckerHigUpdate needs({.samples = 2});
  EXPECT_THROW(needs.step(s.evaluate(UpdateNeed::kStackedJacobian, *cache)), Error);
}

// A rule restored from the JSON text of state() draws the same directions: its steps, sampled
// refreshes included, equal the saving rule's bit for bit. The need alternates as for refresh.
TEST(SampledFactors, ACheckpointResumesTheSameDraws) {
  SampledProblem s(false, 4);
  auto cache = s.network->new_cache();
  const KroneckerHigOptions options{.lr = 0.1, .refresh = 2, .factor_decay = 0.5, .samples = 3};
  KroneckerHigUpdate first(options);
  std::vector<UpdateNeed> needs;
  for (int k = 0; k < 5; ++k) {
    needs.push_back(first.need());
    s.network->parameters() += first.step(s.evaluate(first.need(), *cache)).delta;
  }
  using N = UpdateNeed;
  EXPECT_EQ(needs, (std::vector<N>{N::kWeightedFactors, N::kGradient, N::kWeightedFactors,
                                   N::kGradient, N::kWeightedFactors}));
  const nlohmann::json saved = nlohmann::json::parse(first.state().dump());
  ASSERT_TRUE(saved.contains("directions_rng"));
  KroneckerHigUpdate second(options);
  second.restore(saved, s.network->num_parameters());
  KroneckerHigUpdate fresh(options);  // restored without the generator: other draws
  nlohmann::json without = saved;
  without.erase("directions_rng");
  fresh.restore(without, s.network->num_parameters());
  bool fresh_differs = false;
  for (int k = 0; k < 4; ++k) {
    const BatchState state = s.evaluate(first.need(), *cache);
    const Vector a = first.step(state).delta, b = second.step(state).delta;
    fresh_differs = fresh_differs || !(fresh.step(state).delta == a);
    EXPECT_TRUE(a == b) << k;
    s.network->parameters() += a;
  }
  EXPECT_TRUE(fresh_differs);
  nlohmann::json bad = saved;
  bad["directions_rng"] = "not a state";
  EXPECT_THROW(second.restore(bad, s.network->num_parameters()), Error);
  bad["directions_rng"] = 3;
  EXPECT_THROW(second.restore(bad, s.network->num_parameters()), Error);
}

}  // namespace
}  // namespace physgrad
