#include "physgrad/report/colors.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>


namespace physgrad {

namespace {

constexpr std::array<const char*, 10> kPalette = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                                  "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                                                  "#bcbd22", "#17becf"};

using Rgb = std::array<double, 3>;

// "#rrggbb" of channel values in [0, 255], each rounded.
std::string to_hex(const Rgb& rgb) {
  std::array<char, 8> buf{};
  std::snprintf(buf.data(), buf.size(), "#%02x%02x%02x", static_cast<int>(std::lround(rgb[0])),
                static_cast<int>(std::lround(rgb[1])), static_cast<int>(std::lround(rgb[2])));
  return buf.data();
}

// The channels of "#rrggbb".
Rgb from_hex(const std::string& hex) {
  return {static_cast<double>(std::stoi(hex.substr(1, 2), nullptr, 16)),
          static_cast<double>(std::stoi(hex.substr(3, 2), nullptr, 16)),
          static_cast<double>(std::stoi(hex.substr(5, 2), nullptr, 16))};
}

// Piecewise-linear interpolation between evenly spaced colour stops; t in [0, 1].
template <std::size_t N>
std::string interpolate(const std::array<Rgb, N>& stops, double t) {
  const double s = (std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0) * (N - 1);
  const auto k = std::min<std::size_t>(N - 2, static_cast<std::size_t>(s));
  const double f = s - static_cast<double>(k);
  Rgb rgb{};
  for (std::size_t c = 0; c < 3; ++c) rgb[c] = stops[k][c] * (1 - f) + stops[k + 1][c] * f;
  return to_hex(rgb);
}

}  // namespace

std::string scaled_color(const std::string& hex, double factor) {
  const Rgb rgb = from_hex(hex);
  return to_hex({rgb[0] * factor, rgb[1] * factor, rgb[2] * factor});
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
