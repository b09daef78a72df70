// The rule catalogue and the factories: one table of ids, labels, colours and defaults, every
// option reachable by id through RuleSettings, the docs' option tables generated from it; and the
// first-order learning rules (sgd, adam) with their step-size setters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "learning_fixture.hpp"
#include "physgrad/error.hpp"
#include "physgrad/learn/adam.hpp"
#include "physgrad/learn/hig.hpp"
#include "physgrad/optim/momentum.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;

// The message of the Error `make` throws, or "no error".
std::string error_of(const std::function<void()>& make) {
  try {
    make();
  } catch (const Error& e) {
    return std::string(e.what());
  }
  return std::string("no error");
}

TEST(Catalogue, EveryRuleHasOneEntryWithLabelFormulaAndColour) {
  std::set<std::pair<int, std::string>> seen;
  const auto is_colour = [](const std::string& text) {  // #rrggbb, lower-case hex digits
    return text.size() == 7 && text[0] == '#' &&
           text.find_first_not_of("0123456789abcdef", 1) == std::string::npos;
  };
  for (const RuleInfo& rule : rule_catalogue()) {
    EXPECT_TRUE(seen.insert({static_cast<int>(rule.kind), rule.id}).second) << rule.id;
    EXPECT_FALSE(rule.label.empty()) << rule.id;
    EXPECT_FALSE(rule.formula.empty()) << rule.id;
    EXPECT_TRUE(is_colour(rule.colour)) << rule.id << " " << rule.colour;
    // The factory of the rule's kind builds it, and the rule reports the catalogue's id.
    if (rule.kind == RuleKind::kDirect) {
      EXPECT_EQ(make_optimizer(rule.id)->id(), rule.id);
      EXPECT_EQ(make_optimizer(rule.defaults)->id(), rule.id);
    } else {
      EXPECT_EQ(make_learning_update(rule.id)->id(), rule.id);
      EXPECT_EQ(make_learning_update(rule.defaults)->id(), rule.id);
    }
  }
  EXPECT_EQ(rule_ids(RuleKind::kLearning),
            (std::vector<std::string>{"sgd", "adam", "gn", "hig", "sip", "kfac", "kfac-hig",
                                      "lanczos-gn", "lanczos-hig"}));
  EXPECT_EQ(rule_ids(RuleKind::kDirect).size(), 10u);
  // A rule present in both kinds is drawn in one colour.
  EXPECT_EQ(find_rule(RuleKind::kDirect, "adam").colour,
            find_rule(RuleKind::kLearning, "adam").colour);
}

TEST(Catalogue, UnknownIdsAndOptionsOfTheOtherKindAreErrorsNamingThem) {
  try {
    make_learning_update("lbfgs");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown learning update 'lbfgs' (known: sgd, adam"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(make_optimizer("hig"), Error);
  EXPECT_THROW(make_optimizer(SipOptions{}), Error);
  EXPECT_THROW(make_learning_update(NewtonOptions{}), Error);
  // Adam's options make the direct Adam; with a schedule, the learning one.
  EXPECT_EQ(make_optimizer(AdamOptions{})->id(), "adam");
  EXPECT_THROW(make_learning_update(AdamOptions{}), Error);
  EXPECT_NE(dynamic_cast<AdamUpdate*>(make_learning_update(LearningAdamOptions{}).get()), nullptr);
  EXPECT_THROW(make_optimizer(LearningAdamOptions{}), Error);
}

// Every option params() reports can be set by id through RuleSettings.
TEST(Catalogue, SettingsReachEveryOptionTheRulesReport) {
  const RuleSettings settings{
      {"lr", 0.123},         {"beta", 0.5},          {"beta1", 0.8},
      {"beta2", 0.95},       {"epsilon", 1e-5},      {"rcond", 1e-4},
      {"kappa", 0.25},       {"backend", "normal"},  {"precision", "float"},
      {"eigensolver", "subset"}, {"memory", 4},
      {"c1", 1e-3},          {"c2", 0.5},            {"initial_damping", 0.01},
      {"min_damping", 1e-12}, {"inverse", "ig"},     {"inverse_tolerance", 1e-7},
      {"inverse_iterations", 17}, {"inverse_relative_tolerance", 1e-3},
      {"inverse_function_tolerance", 1e-9}, {"inverse_rcond", 1e-8}, {"y_step", 0.75},
      {"schedule", "plateau"}, {"decay", 0.5}, {"min_lr", 1e-6}, {"patience", 3},
      {"threshold", 0.01},   {"damping", 0.2},       {"refresh", 3},
      {"factor_decay", 0.25}, {"products", 9}, {"samples", 5}};
  nlohmann::json expected(settings);
  expected["initial_step"] = 0.123;  // bfgs and lbfgs take lr as their first trial step
  for (const RuleInfo& rule : rule_catalogue()) {
    // Each kind is given the names its rules have (a name of the other kind is an Error).
    const std::vector<std::string> names = rule_option_names(rule.kind);
    RuleSettings given;
    for (const auto& [name, value] : settings) {
      if (std::find(names.begin(), names.end(), name) != names.end()) given[name] = value;
    }
    const nlohmann::json params =
        rule.kind == RuleKind::kDirect ? make_optimizer(rule.id, given)->params()
                                       : make_learning_update(rule.id, given)->params();
    ASSERT_FALSE(params.empty()) << rule.id;
    for (const auto& [name, value] : params.items()) {
      ASSERT_TRUE(expected.contains(name)) << rule.id << ": option " << name << " has no setting";
      EXPECT_EQ(value, expected.at(name)) << rule.id << ": " << name;
    }
  }
  // Unset settings leave the catalogue's defaults.
  EXPECT_EQ(make_learning_update("hig")->params().at("rcond"), 1e-6);
  EXPECT_EQ(make_learning_update("gn")->params().at("kappa"), 1.0);
}

// params() read back as settings builds the same rule: every option params() reports is one
// settings take, in the same form.
TEST(Catalogue, ParamsGivenAsSettingsGiveTheSameParams) {
  const auto params_of = [](const RuleInfo& rule, const RuleSettings& settings) {
    return rule.kind == RuleKind::kDirect ? make_optimizer(rule.id, settings)->params()
                                          : make_learning_update(rule.id, settings)->params();
  };
  int checked = 0;
  for (const RuleInfo& rule : rule_catalogue()) {
    for (const RuleSettings& changed :
         {RuleSettings{}, RuleSettings{{"lr", 0.3}, {"rcond", 0.25}, {"memory", 3}, {"c2", 0.2},
                                       {"min_damping", 1e-9}, {"beta", 0.1}, {"epsilon", 1e-3}},
          RuleSettings{{"inverse", "analytic"}}, RuleSettings{{"backend", "svd"}}}) {
      const std::vector<std::string> names = rule_option_names(rule.kind);
      RuleSettings given;
      for (const auto& [name, value] : changed) {
        if (std::find(names.begin(), names.end(), name) != names.end()) given[name] = value;
      }
      const nlohmann::json params = params_of(rule, given);
      RuleSettings again;
      for (const auto& [name, value] : params.items()) again[name] = value;
      EXPECT_EQ(params_of(rule, again), params) << rule.id;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 4 * static_cast<int>(rule_catalogue().size()));
}

TEST(Catalogue, AValueOutsideItsRangeIsAnErrorNamingRuleOptionValueAndRange) {
  EXPECT_EQ(error_of([] { make_optimizer("gn", {{"rcond", 1.5}}); }),
            "gn: rcond must be in [0, 1), got 1.5");
  EXPECT_EQ(error_of([] { make_optimizer("lbfgs", {{"memory", 0}}); }),
            "lbfgs: memory must be an integer in [1, 2147483647], got 0");
  EXPECT_EQ(error_of([] { make_optimizer("lbfgs", {{"memory", 2.5}}); }),
            "lbfgs: memory must be an integer in [1, 2147483647], got 2.5");
  // A count beyond the option's int is refused where it is given (it would wrap when stored).
  EXPECT_EQ(error_of([] { make_learning_update("kfac-hig", {{"refresh", 2147483648.0}}); }),
            "kfac-hig: refresh must be an integer in [1, 2147483647], got 2147483648");
  EXPECT_EQ(error_of([] { make_learning_update("lanczos-hig", {{"products", 4294967296.0}}); }),
            "lanczos-hig: products must be an integer in [1, 2147483647], got 4294967296");
  EXPECT_NO_THROW(make_learning_update("kfac-hig", {{"refresh", 2147483647}}));
  EXPECT_EQ(error_of([] { make_optimizer("bfgs", {{"lr", -1}}); }),
            "bfgs: initial_step must be > 0, got -1");
  EXPECT_EQ(error_of([] { make_optimizer("bfgs", {{"c1", 1}}); }),
            "bfgs: c1 must be in (0, 1), got 1");
  EXPECT_EQ(error_of([] { make_optimizer("pg", {{"inverse", "newton"}}); }),
            "pg: inverse must be one of: auto, analytic, time_reversal, lbfgs, ig, got 'newton'");
  EXPECT_EQ(error_of([] { make_learning_update("hig", {{"lr", "fast"}}); }),
            "hig: lr must be > 0, got 'fast'");
  EXPECT_EQ(error_of([] { make_learning_update("sip", {{"inverse_tolerance", 0}}); }),
            "sip: inverse_tolerance must be > 0, got 0");
  // The constructors check the same ranges, naming the rule.
  EXPECT_EQ(error_of([] { Momentum({.beta = 1.0}); }), "momentum: beta must be in [0, 1), got 1");
  EXPECT_EQ(error_of([] { HigUpdate({.cut = {.kappa = 1.0, .rcond = -0.5}}); }),
            "gn: rcond must be in [0, 1), got -0.5");
  EXPECT_EQ(error_of([] { HigUpdate({.cut = {.kappa = NAN, .rcond = 1e-6}}); }),
            "hig: kappa must be finite, got nan");
  EXPECT_EQ(error_of([] { make_learning_update("sgd")->set_learning_rate(0); }),
            "sgd: lr must be > 0, got 0");
}

TEST(Catalogue, AnOptionNameNoRuleOfTheKindHasIsAnErrorNamingIt) {
  EXPECT_EQ(error_of([] { make_optimizer("gd", {{"lrate", 0.1}}); })
                .rfind("unknown rule option 'lrate' (known: beta, beta1, beta2, c1, c2, ", 0),
            0u);
  // kappa is an option of learning rules only.
  EXPECT_EQ(error_of([] { make_optimizer("gn", {{"kappa", 0.5}}); })
                .rfind("unknown rule option 'kappa' (known: ", 0),
            0u);
  // A name another rule of the kind has is left to that rule.
  EXPECT_EQ(make_optimizer("gd", {{"beta", 0.5}})->params(), make_optimizer("gd")->params());
}

// docs/update_rules.md shows the option tables the catalogue generates, verbatim.
TEST(Catalogue, TheDocsShowTheGeneratedOptionTables) {
  std::ifstream file(std::string(PHYSGRAD_SOURCE_DIR) + "/docs/update_rules.md");
  ASSERT_TRUE(file) << "docs/update_rules.md";
  std::stringstream text;
  text << file.rdbuf();
  const std::string doc = text.str();
  for (const auto& [kind, name] :
       {std::pair{RuleKind::kDirect, "direct"}, std::pair{RuleKind::kLearning, "learning"}}) {
    const std::string begin = std::string("<!-- rules:") + name + ":begin -->\n";
    const std::string end = std::string("<!-- rules:") + name + ":end -->";
    const std::size_t from = doc.find(begin), to = doc.find(end);
    ASSERT_NE(from, std::string::npos) << begin;
    ASSERT_NE(to, std::string::npos) << end;
    EXPECT_EQ(doc.substr(from + begin.size(), to - from - begin.size()), rule_table_markdown(kind))
        << "regenerate with: physgrad rules --markdown";
  }
}

TEST(FirstOrderUpdates, SgdAndAdamStepOnTheBatchGradient) {
  const NetworkThroughPhysics s;
  MlpCache cache;
  const BatchState state = s.evaluate(UpdateNeed::kGradient, cache);
  const auto sgd = make_learning_update("sgd", {{"lr", 0.3}});
  EXPECT_EQ(sgd->need(), UpdateNeed::kGradient);
  EXPECT_EQ(sgd->step(state).delta, Vector(-0.3 * state.gradient));
  // Adam's first step: −η g/(|g| + ε) per component (bias-corrected moments g and g²).
  const auto adam = make_learning_update("adam", {{"lr", 0.01}});
  const Vector expected =
      -0.01 * state.gradient.array() / (state.gradient.array().abs() + 1e-8);
  EXPECT_LT((adam->step(state).delta - expected).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(FirstOrderUpdates, TheStepSizeCanBeChangedBetweenSteps) {
  const NetworkThroughPhysics s;
  MlpCache cache;
  const BatchState state = s.evaluate(UpdateNeed::kGradient, cache);
  for (const std::string id : {"sgd", "adam", "sip"}) {
    const auto rule = make_learning_update(id);
    rule->set_learning_rate(0.5);
    EXPECT_EQ(rule->learning_rate(), 0.5) << id;
    EXPECT_EQ(rule->params().at("lr"), 0.5) << id;
    EXPECT_THROW(rule->set_learning_rate(0.0), Error) << id;
  }
  const auto sgd = make_learning_update("sgd", {{"lr", 1.0}});
  const Vector full = sgd->step(state).delta;
  sgd->set_learning_rate(0.25);
  EXPECT_EQ(sgd->step(state).delta, Vector(0.25 * full));
}

}  // namespace
}  // namespace physgrad
