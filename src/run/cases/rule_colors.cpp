#include "physgrad/run/cases/rule_colors.hpp"

#include "physgrad/catalogue.hpp"
#include "physgrad/io/hash.hpp"
#include "physgrad/report/colors.hpp"

namespace physgrad {

std::string color_for(std::string_view key) {
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.id == key) return rule.colour;
  }
  // Adam→rule in the colour the rule's descriptor gives it (Adam→GN, Adam→HIG), else in its
  // rule's colour darkened by a third, or for a rule drawn in black (SIP), in grey.
  const std::string rule = pretrained_rule(std::string(key));
  if (!rule.empty()) {
    const RuleInfo& info = find_rule(RuleKind::kLearning, rule);
    if (!info.pretrained_colour.empty()) return info.pretrained_colour;
    return info.colour == "#000000" ? "#808080" : scaled_color(info.colour, 2.0 / 3.0);
  }
  return palette_color(static_cast<std::size_t>(fnv1a64(key)));
}

}  // namespace physgrad
