// Colours of figures: one fixed colour per update rule, a categorical palette, and colormaps
// for fields (viridis for magnitudes, a blue–white–red map for signed values around 0).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace physgrad {

// The colour of a rule id in every figure: the catalogue's (RuleInfo::colour); of a run Adam
// pretrains before a rule ("adam-hig"), one of its own; a palette colour chosen by a hash of the
// key otherwise; "#rrggbb".
std::string color_for(std::string_view key);
// The index-th colour of a ten-colour categorical palette (cycling).
std::string palette_color(std::size_t index);
// Viridis at t ∈ [0, 1] (clamped), "#rrggbb".
std::string viridis(double t);
// Blue (t = 0) through white (t = ½) to red (t = 1), "#rrggbb".
std::string blue_white_red(double t);

}  // namespace physgrad
