#include "physgrad/report/seed_band.hpp"

#include <algorithm>
#include <cmath>

#include "physgrad/error.hpp"

namespace physgrad {

Series median_band(const std::string& label, const std::vector<Curve>& curves,
                   const std::string& color, bool log, std::size_t max_points) {
  std::vector<double> grid;
  for (const Curve& c : curves) {
    if (c.x.size() != c.y.size()) {
      throw Error("median_band: a curve of '" + label + "' has " + std::to_string(c.x.size()) +
                  " x values but " + std::to_string(c.y.size()) + " y values");
    }
    for (std::size_t k = 0; k < c.x.size(); ++k) {
      if (std::isfinite(c.x[k]) && std::isfinite(c.y[k])) grid.push_back(c.x[k]);
    }
  }
  std::sort(grid.begin(), grid.end());
  grid.erase(std::unique(grid.begin(), grid.end()), grid.end());
  if (grid.size() > max_points && max_points >= 2) {
    std::vector<double> picked;
    for (std::size_t k = 0; k < max_points; ++k) {
      picked.push_back(grid[k * (grid.size() - 1) / (max_points - 1)]);
    }
    grid = std::move(picked);
  }

  Series s{label, {}, {}, color};
  std::vector<std::size_t> at(curves.size(), 0);  // each curve's next unread point
  std::vector<double> held(curves.size(), NAN), values;
  for (const double x : grid) {
    values.clear();
    for (std::size_t c = 0; c < curves.size(); ++c) {
      const Curve& curve = curves[c];
      while (at[c] < curve.x.size() && !(curve.x[at[c]] > x)) {
        if (std::isfinite(curve.x[at[c]]) && std::isfinite(curve.y[at[c]])) {
          held[c] = curve.y[at[c]];
        }
        ++at[c];
      }
      if (std::isfinite(held[c])) values.push_back(held[c]);
    }
    if (values.empty()) continue;
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    double median = values[n / 2];
    if (n % 2 == 0) {
      const double a = values[n / 2 - 1], b = values[n / 2];
      median = log && a > 0 && b > 0 ? std::sqrt(a * b) : 0.5 * (a + b);
    }
    s.x.push_back(x);
    s.y.push_back(median);
    if (curves.size() > 1) {
      s.band_low.push_back(values.front());
      s.band_high.push_back(values.back());
    }
  }
  return s;
}

}  // namespace physgrad
