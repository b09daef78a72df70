// Rules that describe themselves: the catalogue is the descriptors of the rule classes of both
// RuleTypes lists (RuleDescriptor: id, label, formula, colour, defaults, derivative, whose
// settings it takes), a rule built by id reports that id, and experiments look a rule's
// settings up in one place (experiment_setting).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"

namespace physgrad {
namespace {

// Every descriptor of the classes of `Rules`, as {id, colour} in their order.
template <class... Rules>
std::vector<std::pair<std::string, std::string>> described(RuleTypes<Rules...>) {
  std::vector<std::pair<std::string, std::string>> out;
  const auto add = [&out]<class Rule>() {
    for (const auto& rule : Rule::rules()) out.emplace_back(rule.id, rule.colour);
  };
  (add.template operator()<Rules>(), ...);
  return out;
}

TEST(RuleDescriptor, TheCatalogueIsTheDescriptorsOfBothLists) {
  std::vector<std::pair<std::string, std::string>> expected = described(DirectRuleTypes{});
  const std::size_t direct = expected.size();
  for (const auto& entry : described(LearningRuleTypes{})) expected.push_back(entry);
  const std::vector<RuleInfo>& catalogue = rule_catalogue();
  ASSERT_EQ(catalogue.size(), expected.size());
  for (std::size_t i = 0; i < catalogue.size(); ++i) {
    EXPECT_EQ(catalogue[i].kind, i < direct ? RuleKind::kDirect : RuleKind::kLearning) << i;
    EXPECT_EQ(catalogue[i].id, expected[i].first) << i;
    EXPECT_EQ(catalogue[i].colour, expected[i].second) << i;
  }
  // A class of several ids gives each its own defaults.
  EXPECT_EQ(std::get<HigOptions>(find_rule(RuleKind::kLearning, "gn").defaults).cut.kappa, 1.0);
  EXPECT_EQ(std::get<HigOptions>(find_rule(RuleKind::kLearning, "hig").defaults).cut.kappa, 0.5);
}

// Within a kind, ids, labels and colours are non-empty and each rule's own; an id in both kinds
// (adam, gn) is one rule with one label and colour, and no other label or colour is shared.
TEST(RuleDescriptor, EveryRuleHasItsOwnIdLabelAndColour) {
  std::map<std::string, const RuleInfo*> by_id;
  std::map<std::string, std::string> label_owner, colour_owner;
  std::set<std::pair<RuleKind, std::string>> ids;
  for (const RuleInfo& rule : rule_catalogue()) {
    EXPECT_FALSE(rule.id.empty());
    EXPECT_FALSE(rule.label.empty()) << rule.id;
    EXPECT_EQ(rule.colour.size(), 7u) << rule.id;
    EXPECT_TRUE(ids.emplace(rule.kind, rule.id).second) << rule.id << " twice in one kind";
    const auto [seen, first] = by_id.emplace(rule.id, &rule);
    if (!first) {  // the same id in the other kind
      EXPECT_EQ(seen->second->label, rule.label) << rule.id;
      EXPECT_EQ(seen->second->colour, rule.colour) << rule.id;
      continue;
    }
    const auto [label, fresh_label] = label_owner.emplace(rule.label, rule.id);
    EXPECT_TRUE(fresh_label) << rule.id << " has the label of " << label->second;
    const auto [colour, fresh_colour] = colour_owner.emplace(rule.colour, rule.id);
    EXPECT_TRUE(fresh_colour) << rule.id << " has the colour of " << colour->second;
  }
  EXPECT_EQ(by_id.size(), label_owner.size());
}

// A rule built by id reports that id, whatever its options: gn with κ = ½ is gn (with κ = ½ in
// its params()), hig with κ = 1 is hig; built from full options, the id of its options.
TEST(RuleDescriptor, ARuleBuiltByIdReportsThatId) {
  for (const auto& [id, kappa] : std::vector<std::pair<std::string, double>>{
           {"gn", 0.5}, {"hig", 1.0}, {"kfac", 0.5}, {"kfac-hig", 1.0}, {"lanczos-gn", 0.5},
           {"lanczos-hig", 1.0}}) {
    const auto update = make_learning_update(id, {{"kappa", kappa}});
    EXPECT_EQ(update->id(), id) << "κ " << kappa;
    EXPECT_EQ(update->params().at("kappa"), kappa) << id;
    // A change of the step size keeps the id (the options are checked again under it).
    update->set_learning_rate(0.25);
    EXPECT_EQ(update->id(), id);
  }
  EXPECT_EQ(HigUpdate({.cut = {.kappa = 0.5}}, "gn").id(), "gn");
  EXPECT_EQ(HigUpdate({.cut = {.kappa = 1.0}}).id(), "gn");
  EXPECT_EQ(HigUpdate({.cut = {.kappa = 0.25}}).id(), "hig");
  EXPECT_EQ(KroneckerHigUpdate({.cut = {.kappa = 1.0}}).id(), "kfac");
  EXPECT_EQ(make_learning_update(HigOptions{.cut = {.kappa = 1.0}})->id(), "gn");
  // An id the class has no rule of, and an option out of range, are named.
  try {
    HigUpdate({}, "kfac");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "unknown rule id 'kfac' (known: gn, hig)");
  }
  try {
    make_learning_update("gn", {{"kappa", 0.5}, {"lr", -1.0}});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "gn: lr must be > 0, got -1");
  }
}

// The structured approximations take the experiment settings of their exact rule; one lookup.
TEST(RuleDescriptor, AnExperimentsSettingOfARuleFallsBackToItsExactRule) {
  const std::map<std::string, int> table = {{"gn", 1}, {"hig", 2}, {"kfac-hig", 3}};
  const auto setting = [&table](const std::string& id) {
    const int* found = experiment_setting(table, id);
    return found == nullptr ? 0 : *found;
  };
  EXPECT_EQ(setting("gn"), 1);
  EXPECT_EQ(setting("kfac"), 1);
  EXPECT_EQ(setting("lanczos-gn"), 1);
  EXPECT_EQ(setting("lanczos-hig"), 2);
  EXPECT_EQ(setting("kfac-hig"), 3);  // its own first
  EXPECT_EQ(setting("adam"), 0);
  EXPECT_EQ(setting("no-such-rule"), 0);
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.kind != RuleKind::kLearning || rule.settings_from.empty()) continue;
    const RuleInfo& exact = find_rule(RuleKind::kLearning, rule.settings_from);
    EXPECT_TRUE(exact.settings_from.empty()) << rule.id << " → " << exact.id;
  }
}

// What a descriptor says a step forms agrees with what the learning rule asks of its first batch:
// the stacked Jacobian for the rules that form it whole or take products with it, else not.
TEST(RuleDescriptor, TheDerivativeAgreesWithWhatTheRuleNeeds) {
  std::vector<std::string> whole;
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.kind != RuleKind::kLearning) continue;
    const bool jacobian = rule.derivative == RuleDerivative::kJacobian ||
                          rule.derivative == RuleDerivative::kJacobianProducts;
    EXPECT_EQ(make_learning_update(rule.id)->need() == UpdateNeed::kStackedJacobian, jacobian)
        << rule.id;
    EXPECT_NE(rule.derivative, RuleDerivative::kHessian) << rule.id;
    if (rule.derivative == RuleDerivative::kJacobian) whole.push_back(rule.id);
  }
  EXPECT_EQ(whole, (std::vector<std::string>{"gn", "hig"}));
}

}  // namespace
}  // namespace physgrad
