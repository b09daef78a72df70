// The one spectral cut: which directions it keeps, their weights σ^{−κ} (or on λ = σ² with
// damping), the floor, the edge cases of rcond and of the spectrum, and that every rule with a
// cut describes its options alike.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <variant>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/spectral_cut.hpp"

namespace physgrad {
namespace {

Vector values(std::initializer_list<double> list) {
  Vector v(static_cast<Index>(list.size()));
  Index i = 0;
  for (const double x : list) v(i++) = x;
  return v;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SpectralCut, KeepsTheSingularValuesStrictlyAboveTheCut) {
  // τ = 0.25 of σ_max = 4 is 1: the σ = 1 on the cut is dropped, as is everything below it.
  const SpectralCut cut{.kappa = 0.5, .rcond = 0.25};
  const CutSpectrum out = cut_singular_values(cut, values({2, 4, 1, 0.5}));
  EXPECT_EQ(out.kept, 2);
  EXPECT_EQ(out.sigma_max, 4);
  EXPECT_EQ(out.sigma_min_kept, 2);
  EXPECT_EQ(out.condition(), 2);
  EXPECT_DOUBLE_EQ(out.weights(0), 1 / std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(out.weights(1), 0.5);
  EXPECT_EQ(out.weights(2), 0);
  EXPECT_EQ(out.weights(3), 0);
}

TEST(SpectralCut, WeightsAreSigmaToMinusKappa) {
  const Vector sigma = values({3, 0.7, 0.02});
  for (const double kappa : {1.0, 0.5, 2.0, -1.0, 0.0}) {
    const CutSpectrum out = cut_singular_values({.kappa = kappa, .rcond = 0}, sigma);
    ASSERT_EQ(out.kept, 3);
    for (Index i = 0; i < 3; ++i) {
      EXPECT_NEAR(out.weights(i), std::pow(sigma(i), -kappa), 1e-14 * std::pow(sigma(i), -kappa))
          << "kappa " << kappa;
    }
  }
}

TEST(SpectralCut, TheSquaredSpectrumIsCutOnSigmaAndWeightedSigmaToMinusOneMinusKappa) {
  // λ = σ²: the same directions as on σ (τ = 1e-3 keeps σ = 1e-2, drops σ = 1e-4), weighted
  // σ^{−1−κ} = λ^{−(1+κ)/2}.
  const Vector sigma = values({1, 1e-2, 1e-4});
  const Vector lambda = sigma.cwiseProduct(sigma);
  const SpectralCut cut{.kappa = 0.5, .rcond = 1e-3};
  const CutSpectrum on_sigma = cut_singular_values(cut, sigma);
  const CutSpectrum on_lambda = cut_squared(cut, lambda);
  EXPECT_EQ(on_lambda.kept, 2);
  EXPECT_EQ(on_lambda.kept, on_sigma.kept);
  EXPECT_DOUBLE_EQ(on_lambda.sigma_max, 1);
  EXPECT_DOUBLE_EQ(on_lambda.sigma_min_kept, 1e-2);
  EXPECT_NEAR(on_lambda.weights(1), std::pow(1e-4, -0.75), 1e-12 * std::pow(1e-4, -0.75));
  EXPECT_EQ(on_lambda.weights(2), 0);
  // A λ that rounding left slightly below zero reads as 0: dropped, not NaN.
  const CutSpectrum rounded = cut_squared({.rcond = 0}, values({1, -1e-18}));
  EXPECT_EQ(rounded.kept, 1);
  EXPECT_EQ(rounded.weights(1), 0);
}

TEST(SpectralCut, DampingAddsARelativeShiftToEveryKeptEigenvalue) {
  // (λ + d·λ_max)^{−(1+κ)/2} with κ = 1, d = 0.25, λ_max = 4: 1/5 and 1/2; the cut itself is on
  // the undamped λ (λ = 0 stays dropped).
  const SpectralCut cut{.kappa = 1, .rcond = 0, .damping = 0.25};
  const CutSpectrum out = cut_squared(cut, values({4, 1, 0}));
  EXPECT_EQ(out.kept, 2);
  EXPECT_DOUBLE_EQ(out.weights(0), 0.2);
  EXPECT_DOUBLE_EQ(out.weights(1), 0.5);
  EXPECT_EQ(out.weights(2), 0);
}

TEST(SpectralCut, TheFloorRaisesASmallerRcond) {
  const SpectralCut cut{.rcond = 1e-9, .floor = 0.3};
  EXPECT_EQ(cut.cutoff(), 0.3);
  EXPECT_EQ(cut_singular_values(cut, values({1, 0.31, 0.29})).kept, 2);
  EXPECT_EQ((SpectralCut{.rcond = 0.5, .floor = 0.3}).cutoff(), 0.5);
  EXPECT_DOUBLE_EQ(cut.lambda_cut(4), 0.36);
}

TEST(SpectralCut, EdgeCasesOfTheSpectrum) {
  // All zero: nothing is kept even at rcond = 0 (σ > 0·0 fails), and the condition is 0.
  for (const CutSpectrum& zero : {cut_singular_values({.rcond = 0}, Vector::Zero(3)),
                                  cut_squared({.rcond = 0}, Vector::Zero(3))}) {
    EXPECT_EQ(zero.kept, 0);
    EXPECT_EQ(zero.condition(), 0);
    EXPECT_EQ(zero.weights, Vector::Zero(3));
  }
  EXPECT_EQ(cut_singular_values({}, Vector()).kept, 0);
  // rcond = 0 keeps every positive σ, however small.
  EXPECT_EQ(cut_singular_values({.rcond = 0}, values({1, 1e-300, 0})).kept, 2);
  // A NaN or an infinite value in the spectrum is a NumericalError, not a silent cut.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(cut_singular_values({}, values({1, nan})), NumericalError);
  EXPECT_THROW(cut_squared({}, values({nan, 1})), NumericalError);
  Vector c = values({1, 1});
  EXPECT_THROW(cut_symmetric({}, values({1, INFINITY}), c), NumericalError);
}

TEST(SpectralCut, CheckNamesTheOffendingValue) {
  EXPECT_EQ(error_of([] { SpectralCut{.rcond = 1}.check("x"); }),
            "x: rcond must be in [0, 1), got 1");
  EXPECT_EQ(error_of([] { SpectralCut{.rcond = -0.5}.check("x"); }),
            "x: rcond must be in [0, 1), got -0.5");
  EXPECT_EQ(error_of([] { SpectralCut{.rcond = NAN}.check("x"); }),
            "x: rcond must be in [0, 1), got nan");
  EXPECT_EQ(error_of([] { SpectralCut{.kappa = INFINITY}.check("x"); }),
            "x: kappa must be finite, got inf");
  EXPECT_EQ(error_of([] { SpectralCut{.damping = -1}.check("x"); }),
            "x: damping must be ≥ 0 and finite, got -1");
  EXPECT_EQ(error_of([] { SpectralCut{.floor = 1}.check("x"); }),
            "x: the rcond floor must be in [0, 1), got 1");
  EXPECT_EQ(error_of([] { SpectralCut{.kappa = 0.5, .rcond = 0}.check("x"); }), "(no error)");
}

TEST(SpectralCut, SymmetricSolveCutsAbsoluteEigenvaluesAsSigmaSquaredAndKeepsTheSign) {
  // |λ| = σ²: τ = 1e-3 keeps |λ| > 1e-6·4, so −4 and 1e-5 stay and 1e-7 goes; κ = 1 divides.
  const Vector lambda = values({-4, 1e-5, 1e-7});
  Vector c = values({2, 3, 5});
  const CutSpectrum out = cut_symmetric({.kappa = 1, .rcond = 1e-3}, lambda, c);
  EXPECT_EQ(out.kept, 2);
  EXPECT_EQ(c(0), 2 / -4.0);
  EXPECT_EQ(c(1), 3 / 1e-5);
  EXPECT_EQ(c(2), 0);
  // κ = ½ with damping: sign(λ)(|λ| + d|λ|max)^{−3/4}.
  Vector d = values({1, 1, 1});
  cut_symmetric({.kappa = 0.5, .rcond = 0, .damping = 0.25}, values({-4, 1, 0}), d);
  EXPECT_NEAR(d(0), -std::pow(5.0, -0.75), 1e-15);
  EXPECT_NEAR(d(1), std::pow(2.0, -0.75), 1e-15);
  EXPECT_EQ(d(2), 0);
  Vector wrong(2);
  EXPECT_EQ(error_of([&] { cut_symmetric({}, lambda, wrong); }),
            "spectral cut: 3 eigenvalues but 2 coefficients");
}

// Every rule of the catalogue with a cut option describes it as the cut does: one name, range
// and help, so --rcond means the same for each.
TEST(SpectralCut, EveryRuleDescribesItsCutOptionsAlike) {
  int rcond_rules = 0;
  for (const RuleInfo& rule : rule_catalogue()) {
    for (const OptionDescription& option : rule_options(rule)) {
      for (const OptionDescription* cut :
           {&kappa_option_description(), &rcond_option_description(),
            &damping_option_description()}) {
        if (option.name != cut->name) continue;
        rcond_rules += option.name == "rcond";
        EXPECT_EQ(option.help, cut->help) << rule.id << " " << option.name;
        EXPECT_EQ(option.range.text(), cut->range.text()) << rule.id << " " << option.name;
      }
    }
  }
  EXPECT_EQ(rcond_rules, 9);  // newton, gn, ig; gn, hig, kfac, kfac-hig, lanczos-gn, lanczos-hig
}

// The learning rules hold their cut as one SpectralCut: the options kappa, rcond and damping are
// its members, set by name and reported by params(); the κ = 1 id of each class has the cut of
// its κ = ½ id at κ = 1, everything else the same.
TEST(SpectralCut, TheLearningRulesOptionsAreTheirCutsMembers) {
  const RuleSettings settings = {{"kappa", 0.75}, {"rcond", 0.25}, {"damping", 0.125}};
  const auto hig = std::get<HigOptions>(with_settings(find_rule(RuleKind::kLearning, "hig"),
                                                      settings));
  EXPECT_EQ(hig.cut.kappa, 0.75);
  EXPECT_EQ(hig.cut.rcond, 0.25);
  EXPECT_EQ(hig.cut.damping, 0.0);  // hig has no damping option
  const auto kfac = std::get<KroneckerHigOptions>(
      with_settings(find_rule(RuleKind::kLearning, "kfac-hig"), settings));
  EXPECT_EQ(kfac.cut.kappa, 0.75);
  EXPECT_EQ(kfac.cut.rcond, 0.25);
  EXPECT_EQ(kfac.cut.damping, 0.125);
  const auto lanczos = std::get<LanczosHigOptions>(
      with_settings(find_rule(RuleKind::kLearning, "lanczos-hig"), settings));
  EXPECT_EQ(lanczos.cut.rcond, 0.25);
  const nlohmann::json params = KroneckerHigUpdate(kfac).params();
  EXPECT_EQ(params.at("kappa"), 0.75);
  EXPECT_EQ(params.at("rcond"), 0.25);
  EXPECT_EQ(params.at("damping"), 0.125);
  for (const auto& [one, half] : {std::pair{"gn", "hig"}, std::pair{"kfac", "kfac-hig"},
                                  std::pair{"lanczos-gn", "lanczos-hig"}}) {
    const auto cut_of = [](const char* id) {
      return std::visit(
          [](const auto& o) -> SpectralCut {
            if constexpr (requires { o.cut; }) {
              return o.cut;
            } else {
              return {};
            }
          },
          find_rule(RuleKind::kLearning, id).defaults);
    };
    const SpectralCut a = cut_of(one), b = cut_of(half);
    EXPECT_EQ(a.kappa, 1.0) << one;
    EXPECT_EQ(b.kappa, 0.5) << half;
    EXPECT_EQ(a.rcond, b.rcond) << one;
    EXPECT_EQ(a.damping, b.damping) << one;
    EXPECT_EQ(a.floor, b.floor) << one;
  }
  EXPECT_EQ(KroneckerHigOptions{}.cut.damping, 1e-2);
  EXPECT_EQ(HigOptions{}.cut.rcond, 1e-6);
}

}  // namespace
}  // namespace physgrad
