// The colour a rule is drawn in, in every figure and on the index: the one its class's descriptor
// gives it (Rule::rules(), read through the catalogue), written nowhere else.
#pragma once

#include <string>
#include <string_view>

namespace physgrad {

// "#rrggbb" of a rule id: its descriptor's colour; of a run Adam pretrains before a rule
// ("adam-hig"), the descriptor's pretrained_colour or the rule's darkened; for any other key a
// palette colour chosen by a hash of it.
std::string color_for(std::string_view key);

}  // namespace physgrad
