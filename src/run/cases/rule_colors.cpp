#include "physgrad/run/cases/rule_colors.hpp"

#include "physgrad/catalogue.hpp"
#include "physgrad/io/hash.hpp"
#include "physgrad/report/colors.hpp"

namespace physgrad {

std::string color_for(std::string_view key) {
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.id == key) return rule.colour;
  }
  // Adam→GN and Adam→HIG as they have always been drawn; any other Adam→rule in its rule's
  // colour darkened by a third, or for a rule drawn in black (SIP), in grey.
  if (key == "adam-gn") return "#c51b7d";
  if (key == "adam-hig") return "#7b3294";
  const std::string rule = pretrained_rule(std::string(key));
  if (!rule.empty()) {
    const std::string colour = find_rule(RuleKind::kLearning, rule).colour;
    return colour == "#000000" ? "#808080" : scaled_color(colour, 2.0 / 3.0);
  }
  return palette_color(static_cast<std::size_t>(fnv1a64(key)));
}

}  // namespace physgrad
