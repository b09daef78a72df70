// A direct rule added to the catalogue from outside the library — its class in one header
// (sign_descent_rule.hpp, with its descriptor) and one add_direct_rule line: the factories, the
// option lists, the settings by name with their range checks, the tables and the figures'
// colours then take it as a built-in rule; and every rule's params() is its option list.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/run/cases/direct_runs.hpp"
#include "physgrad/run/cases/rule_colors.hpp"
#include "sign_descent_rule.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

using testing::SignDescent;

bool has(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

TEST(AddedRule, OneLineMakesARuleOfTheCatalogue) {
  const std::vector<std::string> before = rule_ids(RuleKind::kDirect);
  const std::string table_before = rule_table_markdown(RuleKind::kDirect);
  {
    const AddedRule added = add_direct_rule<SignDescent>();  // as SignDescent::rules() says

    std::vector<std::string> expected = before;
    expected.push_back("sign");
    EXPECT_EQ(rule_ids(RuleKind::kDirect), expected);
    EXPECT_EQ(find_rule(RuleKind::kDirect, "sign").label, "Sign descent");
    EXPECT_THROW(find_rule(RuleKind::kLearning, "sign"), Error);

    // Built by id with the defaults or with settings, which are checked against the range.
    EXPECT_EQ(make_optimizer("sign")->id(), "sign");
    EXPECT_EQ(make_optimizer("sign")->params(), (nlohmann::json{{"lr", 0.1}}));
    EXPECT_EQ(make_optimizer("sign", {{"lr", 0.25}})->params(), (nlohmann::json{{"lr", 0.25}}));
    EXPECT_EQ(make_optimizer(find_rule(RuleKind::kDirect, "sign").defaults)->id(), "sign");
    try {
      make_optimizer("sign", {{"lr", -1.0}});
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), "sign: lr must be > 0, got -1");
    }
    // A setting of another direct rule passes over it, as it does over the built-in ones.
    EXPECT_EQ(make_optimizer("sign", {{"rcond", 0.5}})->params(), (nlohmann::json{{"lr", 0.1}}));
    EXPECT_THROW(make_learning_update(find_rule(RuleKind::kDirect, "sign").defaults), Error);

    // The option lists and the docs' table know it.
    EXPECT_TRUE(has(shared_rule_option("lr", RuleKind::kDirect).rules, "sign"));
    EXPECT_EQ(rule_defaults_text(find_rule(RuleKind::kDirect, "sign")), "lr = 0.1");
    EXPECT_EQ(rule_table_markdown(RuleKind::kDirect),
              table_before + "| `sign` | Sign descent | Δx = −η sign(∂L/∂x) | lr = 0.1 |\n");

    // Its steps are −η sign(∇L): from (0.48, 0.84) towards 0 on P(x) = (x₁, 10 x₂).
    const testing::LinearSimulator simulator(Vector{{1.0, 10.0}}.asDiagonal());
    const L2Loss loss;
    const Objective objective(simulator, loss, Vector::Zero(2));
    MinimizeOptions options;
    options.max_iterations = 3;
    const MinimizeSummary s =
        minimize(*make_optimizer("sign", {{"lr", 0.125}}), objective, Vector{{0.48, 0.84}}, options);
    ASSERT_EQ(s.history.size(), 4u);
    EXPECT_EQ(s.params, (nlohmann::json{{"lr", 0.125}}));
    for (std::size_t k = 1; k < s.history.size(); ++k) {
      const Vector& x = s.history[k - 1].x;
      const Vector expected_step = -0.125 * objective.gradient(x).cwiseSign();
      EXPECT_LT((s.history[k].x - x - expected_step).norm(), 1e-15) << "iteration " << k;
    }
  }
  // Gone with its handle.
  EXPECT_EQ(rule_ids(RuleKind::kDirect), before);
  EXPECT_EQ(rule_table_markdown(RuleKind::kDirect), table_before);
  EXPECT_THROW(make_optimizer("sign"), Error);
}

// The colour of the rule's descriptor is the one the figures draw it in while it is added (no
// other rule has it); without the rule the same figure has it nowhere.
TEST(AddedRule, ItsDescriptorsColourShowsInTheFigures) {
  const std::string colour = SignDescent::rules().front().colour;
  const testing::LinearSimulator simulator(Vector{{1.0, 10.0}}.asDiagonal());
  const L2Loss loss;
  const Objective objective(simulator, loss, Vector::Zero(2));
  MinimizeOptions options;
  options.max_iterations = 3;
  const Vector x0{{0.48, 0.84}};
  const auto figure = [&] {
    SignDescent rule;
    const run::DirectResult result{{"sign", "Sign descent", {}},
                                   minimize(rule, objective, x0, options), objective.value(x0)};
    return run::loss_curves_svg({result}, "loss");
  };
  {
    const AddedRule added = add_direct_rule<SignDescent>();
    EXPECT_EQ(find_rule(RuleKind::kDirect, "sign").colour, colour);
    EXPECT_EQ(color_for("sign"), colour);
    for (const RuleInfo& rule : rule_catalogue()) {
      if (rule.id != "sign") {
        EXPECT_NE(color_for(rule.id), colour) << rule.id;
      }
    }
    EXPECT_NE(figure().find("stroke=\"" + colour + "\""), std::string::npos);
  }
  EXPECT_NE(color_for("sign"), colour);
  EXPECT_EQ(figure().find(colour), std::string::npos);
}

TEST(AddedRule, AnIdTakenOrNotTheRulesOwnIsAnError) {
  try {
    const AddedRule taken = add_direct_rule<SignDescent>("gd", "GD again", "Δx", "#000000");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "add_direct_rule: the direct rules have the id 'gd' already");
  }
  try {
    const AddedRule other = add_direct_rule<SignDescent>("signs", "Signs", "Δx", "#000000");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "add_direct_rule: the rule added as 'signs' reports the id 'sign'");
  }
  EXPECT_FALSE(has(rule_ids(RuleKind::kDirect), "signs"));
  EXPECT_EQ(make_optimizer("gd")->id(), "gd");
}

// Every rule reports in params() the options of its list (those that apply) with their values,
// each within its range: params() is read from the list, not written beside it.
TEST(AddedRule, EveryRulesParamsAreItsOptionList) {
  for (const RuleInfo& rule : rule_catalogue()) {
    std::set<std::string> names;
    for (const OptionDescription& option : rule_options(rule)) names.insert(option.name);
    const nlohmann::json params = rule.kind == RuleKind::kDirect
                                      ? make_optimizer(rule.id)->params()
                                      : make_learning_update(rule.id)->params();
    ASSERT_FALSE(params.empty()) << rule.id;
    for (const OptionDescription& option : rule_options(rule)) {
      if (!params.contains(option.name)) continue;  // an option that does not apply
      EXPECT_TRUE(option.range.contains(params.at(option.name))) << rule.id << ": " << option.name;
    }
    for (const auto& [name, value] : params.items()) {
      EXPECT_TRUE(names.count(name)) << rule.id << " reports " << name << ", not in its list";
    }
  }
}

}  // namespace
}  // namespace physgrad
