// Which series a line plot says another "coincides with" (report/line_plot.hpp): only curves, so
// that a series of a single point lying on a curve is not called a curve it coincides with.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "physgrad/report/line_plot.hpp"

namespace physgrad {
namespace {

// time-reversal's PG (IG inverse) stops after one point, which lies on Gauss-Newton's curve drawn
// after it: Gauss-Newton's entry names no coincidence, and the point keeps a marker of its own.
TEST(LinePlotCoincides, ASinglePointCoincidesWithNoCurve) {
  std::vector<double> x, y;
  for (int k = 0; k <= 20; ++k) {
    x.push_back(k);
    y.push_back(10 - 0.4 * k);
  }
  const Series point{"PG (IG inverse)", {0}, {10}, "#1f77b4", true};
  const Series curve{"Gauss-Newton", x, y, "#ff7f0e", true};
  const std::string svg = line_plot_svg({point, curve}, {});
  EXPECT_EQ(svg.find("coincides"), std::string::npos) << svg;
  EXPECT_NE(svg.find(">Gauss-Newton<"), std::string::npos) << svg;
  // Drawn the other way round, the point does not coincide with the curve either.
  const std::string reversed = line_plot_svg({curve, point}, {});
  EXPECT_EQ(reversed.find("coincides"), std::string::npos) << reversed;
  // Two curves along each other still do.
  const Series twin{"LM", x, y, "#2ca02c", true};
  const std::string both = line_plot_svg({curve, twin}, {});
  EXPECT_NE(both.find(">LM (coincides with Gauss-Newton)<"), std::string::npos) << both;
}

}  // namespace
}  // namespace physgrad
