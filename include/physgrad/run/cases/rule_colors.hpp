// The colour a rule is drawn in, in every figure and on the index: the catalogue's, where each
// rule's colour is written once (RuleInfo::colour).
#pragma once

#include <string>
#include <string_view>

namespace physgrad {

// "#rrggbb" of a rule id: the catalogue's colour; of a run Adam pretrains before a rule
// ("adam-hig"), one of its own; for any other key a palette colour chosen by a hash of it.
std::string color_for(std::string_view key);

}  // namespace physgrad
