#include "physgrad/report/isolines.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <unordered_map>

#include "physgrad/error.hpp"

namespace physgrad {

std::vector<std::vector<std::pair<double, double>>> isolines(const Grid2D& grid, double level) {
  check_grid(grid);
  if (!std::isfinite(level)) {
    throw Error("isolines: level " + std::to_string(level) + " is not finite");
  }
  const long long nx = grid.nx, ny = grid.ny;
  const auto value = [&](long long node) { return grid.values[static_cast<std::size_t>(node)]; };

  // Edge 2n joins node n = j*nx + i to its right neighbour, edge 2n+1 to the one above. The
  // crossing on an edge depends only on the edge, so both cells sharing it agree exactly.
  const auto crossing = [&](long long edge) -> std::pair<double, double> {
    const long long a = edge / 2, b = edge % 2 == 0 ? a + 1 : a + nx;
    const double t = (level - value(a)) / (value(b) - value(a));
    const double i = static_cast<double>(a % nx) + (edge % 2 == 0 ? t : 0);
    const double j = static_cast<double>(a / nx) + (edge % 2 == 0 ? 0 : t);
    return {grid.x_min + i * (grid.x_max - grid.x_min) / static_cast<double>(nx - 1),
            grid.y_min + j * (grid.y_max - grid.y_min) / static_cast<double>(ny - 1)};
  };

  std::vector<std::array<long long, 2>> segments;
  for (long long j = 0; j + 1 < ny; ++j) {
    for (long long i = 0; i + 1 < nx; ++i) {
      const long long n = j * nx + i;
      // Corners counter-clockwise from the bottom left; edges bottom, right, top, left.
      const std::array<double, 4> v{value(n), value(n + 1), value(n + nx + 1), value(n + nx)};
      if (!std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); })) continue;
      const std::array<long long, 4> edges{2 * n, 2 * (n + 1) + 1, 2 * (n + nx), 2 * n + 1};
      std::vector<long long> crossed;
      int above = 0;
      for (std::size_t c = 0; c < 4; ++c) {
        if ((v[c] > level) != (v[(c + 1) % 4] > level)) crossed.push_back(edges[c]);
        above |= (v[c] > level ? 1 : 0) << c;
      }
      if (crossed.size() == 2) {
        segments.push_back({crossed[0], crossed[1]});
      } else if (crossed.size() == 4) {
        // Saddle: the mean decides which pair of opposite corners is connected.
        const bool centre_above = (v[0] + v[1] + v[2] + v[3]) / 4 > level;
        if ((above == 5) == centre_above) {  // cut off the bottom-right and top-left corners
          segments.push_back({crossed[0], crossed[1]});
          segments.push_back({crossed[2], crossed[3]});
        } else {  // cut off the bottom-left and top-right corners
          segments.push_back({crossed[3], crossed[0]});
          segments.push_back({crossed[1], crossed[2]});
        }
      }
    }
  }

  // Each edge touches at most two segments: chain them, open chains from their ends first.
  std::unordered_map<long long, std::array<int, 2>> touching;
  for (int s = 0; s < static_cast<int>(segments.size()); ++s) {
    for (const long long e : segments[static_cast<std::size_t>(s)]) {
      auto [it, added] = touching.try_emplace(e, std::array<int, 2>{s, -1});
      if (!added) it->second[1] = s;
    }
  }
  std::vector<bool> used(segments.size(), false);
  std::vector<std::vector<std::pair<double, double>>> lines;
  const auto chain = [&](int s, long long from) {
    auto& line = lines.emplace_back(1, crossing(from));
    while (s >= 0 && !used[static_cast<std::size_t>(s)]) {
      used[static_cast<std::size_t>(s)] = true;
      const auto& seg = segments[static_cast<std::size_t>(s)];
      from = seg[0] == from ? seg[1] : seg[0];
      line.push_back(crossing(from));
      const auto& next = touching[from];
      s = next[0] == s ? next[1] : next[0];
    }
  };
  for (int s = 0; s < static_cast<int>(segments.size()); ++s) {
    for (const long long e : segments[static_cast<std::size_t>(s)]) {
      if (!used[static_cast<std::size_t>(s)] && touching[e][1] < 0) chain(s, e);
    }
  }
  for (int s = 0; s < static_cast<int>(segments.size()); ++s) {
    if (!used[static_cast<std::size_t>(s)]) chain(s, segments[static_cast<std::size_t>(s)][0]);
  }
  return lines;
}

}  // namespace physgrad
