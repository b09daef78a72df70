#include "physgrad/report/colors.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <utility>

#include "physgrad/io/hash.hpp"

namespace physgrad {

namespace {

constexpr std::array<const char*, 10> kPalette = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                                  "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                                                  "#bcbd22", "#17becf"};

using Rgb = std::array<double, 3>;

// Piecewise-linear interpolation between evenly spaced colour stops; t in [0, 1].
template <std::size_t N>
std::string interpolate(const std::array<Rgb, N>& stops, double t) {
  const double s = (std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0) * (N - 1);
  const auto k = std::min<std::size_t>(N - 2, static_cast<std::size_t>(s));
  const double f = s - static_cast<double>(k);
  std::array<int, 3> rgb{};
  for (std::size_t c = 0; c < 3; ++c) {
    rgb[c] = static_cast<int>(std::lround(stops[k][c] * (1 - f) + stops[k + 1][c] * f));
  }
  std::array<char, 8> buf{};
  std::snprintf(buf.data(), buf.size(), "#%02x%02x%02x", rgb[0], rgb[1], rgb[2]);
  return buf.data();
}

}  // namespace

std::string color_for(std::string_view key) {
  static constexpr std::array<std::pair<std::string_view, const char*>, 15> kFixed{{
      {"gd", "#1f77b4"},
      {"sgd", "#6baed6"},
      {"momentum", "#17becf"},
      {"adam", "#ff7f0e"},
      {"newton", "#d62728"},
      {"bfgs", "#9467bd"},
      {"lbfgs", "#c5a3e0"},
      {"gn", "#8c564b"},
      {"lm", "#e377c2"},
      {"ig", "#2ca02c"},
      {"pg", "#bcbd22"},
      {"hig", "#00633a"},
      {"sip", "#000000"},
      {"adam-gn", "#c51b7d"},  // learning runs pretrained with Adam (catalogue.hpp)
      {"adam-hig", "#7b3294"},
  }};
  for (const auto& [id, color] : kFixed) {
    if (id == key) return color;
  }
  return kPalette[fnv1a64(key) % kPalette.size()];
}

std::string palette_color(std::size_t index) { return kPalette[index % kPalette.size()]; }

std::string viridis(double t) {
  static constexpr std::array<Rgb, 9> kStops{{{68, 1, 84},
                                              {71, 45, 123},
                                              {59, 82, 139},
                                              {44, 114, 142},
                                              {33, 145, 140},
                                              {40, 174, 128},
                                              {94, 201, 98},
                                              {173, 220, 48},
                                              {253, 231, 37}}};
  return interpolate(kStops, t);
}

std::string blue_white_red(double t) {
  static constexpr std::array<Rgb, 5> kStops{
      {{33, 102, 172}, {146, 197, 222}, {247, 247, 247}, {244, 165, 130}, {178, 24, 43}}};
  return interpolate(kStops, t);
}

}  // namespace physgrad
