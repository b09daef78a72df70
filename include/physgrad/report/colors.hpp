// Colours of figures: a categorical palette, and colormaps for fields (viridis for magnitudes,
// a blue–white–red map for signed values around 0). A rule's colour: run/rule_colors.hpp.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace physgrad {

// "#rrggbb" with each channel of `hex` ("#rrggbb") multiplied by factor ∈ [0, 1] (rounded).
std::string scaled_color(const std::string& hex, double factor);
// The index-th colour of a ten-colour categorical palette (cycling).
std::string palette_color(std::size_t index);
// Viridis at t ∈ [0, 1] (clamped), "#rrggbb".
std::string viridis(double t);
// Blue (t = 0) through white (t = ½) to red (t = 1), "#rrggbb".
std::string blue_white_red(double t);

}  // namespace physgrad
