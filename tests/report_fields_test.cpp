// Figures of fields: isolines (marching squares), loss landscapes with trajectories, panels of
// heat maps in one colour range, and the median band over seeds; each checked in its wide layout
// and as a whole document (both layouts) by the SVG checker.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/run/cases/rule_colors.hpp"
#include "physgrad/report/field_plot.hpp"
#include "physgrad/report/isolines.hpp"
#include "physgrad/report/landscape.hpp"
#include "physgrad/report/seed_band.hpp"
#include "physgrad/report/svg_document.hpp"
#include "svg_check.hpp"

namespace physgrad {
namespace {

bool has_long_coordinate(const std::string& svg) {
  std::size_t digits = 0;
  char before = ' ';
  for (const char c : svg) {
    if (c >= '0' && c <= '9') {
      if (++digits >= 5 && (before == ' ' || before == ',' || before == 'M' || before == '-')) {
        return true;
      }
    } else {
      digits = 0;
      before = c;
    }
  }
  return false;
}

namespace fs = std::filesystem;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
using testing::count;
using testing::has_non_finite_text;




Grid2D radial_grid(int n) {
  Grid2D g{-1, 1, -1, 1, n, n, {}};
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = -1 + 2.0 * i / (n - 1), y = -1 + 2.0 * j / (n - 1);
      g.values.push_back(x * x + y * y);
    }
  }
  return g;
}

TEST(SvgIsolines, CircleOfRadiusHalfOnRadialField) {
  const Grid2D grid = radial_grid(41);
  const auto lines = isolines(grid, 0.25);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_GT(lines[0].size(), 20u);
  EXPECT_EQ(lines[0].front(), lines[0].back());  // closed
  for (const auto& line : lines) {
    for (const auto& [x, y] : line) EXPECT_NEAR(std::hypot(x, y), 0.5, 0.02);
  }
}

TEST(SvgIsolines, OpenCurvesEndOnTheBoundaryAndOutOfRangeLevelsAreEmpty) {
  const Grid2D grid = radial_grid(21);
  // Level 1.5 cuts the four corners off: four open arcs of radius √1.5.
  const auto arcs = isolines(grid, 1.5);
  ASSERT_EQ(arcs.size(), 4u);
  for (const auto& arc : arcs) {
    EXPECT_NE(arc.front(), arc.back());
    for (const auto& [x, y] : arc) EXPECT_NEAR(std::hypot(x, y), std::sqrt(1.5), 0.03);
  }
  EXPECT_TRUE(isolines(grid, 5.0).empty());
  EXPECT_TRUE(isolines(grid, -1.0).empty());
  EXPECT_THROW(isolines(grid, kNaN), Error);
}

TEST(SvgIsolines, SaddleCellsGiveTwoSeparateCurves) {
  // f = x·y has a saddle at the origin; level 0.1 gives two hyperbola branches.
  Grid2D grid{-1, 1, -1, 1, 4, 4, {}};
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 4; ++i) grid.values.push_back((-1 + 2.0 * i / 3) * (-1 + 2.0 * j / 3));
  }
  const auto lines = isolines(grid, 0.1);
  ASSERT_EQ(lines.size(), 2u);
  for (const auto& line : lines) {
    for (const auto& [x, y] : line) EXPECT_GT(x * y, 0.0);  // each point in quadrant I or III
  }
}

TEST(SvgLandscape, RadialFieldHasOneIsolinePerLevelAndTrajectories) {
  const Grid2D grid = radial_grid(41);
  const std::vector<Trajectory> trajectories{
      {"gd", {0.9, 0.5, 0.2, kNaN, 0.05}, {0.8, 0.4, 0.1, 0.0, 0.02}, color_for("gd")},
      {"diverging newton", {-0.5, -2, 1e6}, {0.5, 3, -1e9}, ""}};
  LandscapeOptions options;
  options.title = "x² + y²";
  options.markers = {{0, 0, "minimum"}};
  for (const bool log : {true, false}) {
    options.log_levels = log;
    const std::string both = landscape_svg(grid, trajectories, options);
    EXPECT_TRUE(testing::SvgChecker::check(both).empty());
    const std::string svg = svg::layouts(both).wide;
    EXPECT_EQ(svg.rfind("<svg", 0), 0u);
    EXPECT_EQ(count(svg, "class=\"isoline\""), static_cast<std::size_t>(options.levels));
    EXPECT_NE(svg.find(">gd<"), std::string::npos);
    // It leaves the view after its first step: drawn to there, and the step named.
    EXPECT_NE(svg.find(">diverging newton (leaves the view at step 1)<"), std::string::npos);
    EXPECT_NE(svg.find(">minimum<"), std::string::npos);
    EXPECT_NE(svg.find("clipPath"), std::string::npos);
    EXPECT_FALSE(has_non_finite_text(svg));
    // The far-away iterates are cut to a neighbourhood of the plot, not printed as is.
    EXPECT_FALSE(has_long_coordinate(svg));
  }
}

TEST(SvgLandscape, LargeGridStaysSmall) {
  Grid2D grid{-3, 3, -2, 2, 80, 80, {}};
  for (int j = 0; j < 80; ++j) {
    for (int i = 0; i < 80; ++i) {
      const double x = -3 + 6.0 * i / 79, y = -2 + 4.0 * j / 79;
      grid.values.push_back(std::pow(1 - x, 2) + 100 * std::pow(y - x * x, 2));  // Rosenbrock
    }
  }
  Trajectory t{"adam", {}, {}, color_for("adam")};
  for (int k = 0; k < 500; ++k) {
    t.x.push_back(-2 + 3.0 * k / 499);
    t.y.push_back(1.5 * std::cos(k / 50.0));
  }
  const std::string svg = landscape_svg(grid, {t}, {});
  EXPECT_LT(svg.size(), 2 * 400'000u);  // two layouts
  EXPECT_FALSE(has_non_finite_text(svg));
}

TEST(SvgLandscape, ConstantAndPartlyNonFiniteFieldsAreHandled) {
  Grid2D flat{0, 1, 0, 1, 3, 3, std::vector<double>(9, 2.0)};
  EXPECT_FALSE(has_non_finite_text(landscape_svg(flat, {}, {})));
  Grid2D holes = radial_grid(9);
  holes.values[40] = kNaN;
  holes.values[3] = kInf;
  holes.values[10] = -5;
  EXPECT_FALSE(has_non_finite_text(landscape_svg(holes, {}, {})));
}

TEST(SvgLandscape, InvalidInputThrows) {
  Grid2D grid = radial_grid(5);
  grid.values.pop_back();
  EXPECT_THROW(landscape_svg(grid, {}, {}), Error);
  EXPECT_THROW(isolines(grid, 0.5), Error);
  EXPECT_THROW(landscape_svg({0, 1, 0, 1, 1, 2, {0, 0}}, {}, {}), Error);
  EXPECT_THROW(landscape_svg({1, 1, 0, 1, 2, 2, {0, 0, 0, 0}}, {}, {}), Error);
  EXPECT_THROW(landscape_svg(radial_grid(5), {{"t", {1, 2}, {1}, ""}}, {}), Error);
  LandscapeOptions options;
  options.levels = -1;
  EXPECT_THROW(landscape_svg(radial_grid(5), {}, options), Error);
}

TEST(SvgLandscape, ClipPathIdsDifferBetweenFigures) {
  const std::string a = landscape_svg(radial_grid(5), {}, {});
  const std::string b = line_plot_svg({{"s", {0, 1}, {0, 1}}}, {});
  const auto id = [](const std::string& svg) {
    const auto start = svg.find("clipPath id=\"") + 13;
    return svg.substr(start, svg.find('"', start) - start);
  };
  EXPECT_NE(id(a), id(b));
}

TEST(SeedBand, MedianAndMinMaxOverCurvesSampledAtDifferentX) {
  const std::vector<Curve> curves{{{0, 1, 2}, {1, 2, 3}}, {{0, 1.5}, {4, 5}}, {{0, 2}, {7, 8}}};
  const Series s = median_band("m", curves, "#000000", false);
  EXPECT_EQ(s.x, (std::vector<double>{0, 1, 1.5, 2}));
  EXPECT_EQ(s.y, (std::vector<double>{4, 4, 5, 5}));  // the second curve holds 5 after x = 1.5
  EXPECT_EQ(s.band_low, (std::vector<double>{1, 2, 2, 3}));
  EXPECT_EQ(s.band_high, (std::vector<double>{7, 7, 7, 8}));
  // Two curves on a log axis: the geometric mean of the middle two; one curve: no band.
  const Series even = median_band("e", {{{0}, {1e-4}}, {{0}, {1e-2}}}, "", true);
  EXPECT_NEAR(even.y[0], 1e-3, 1e-15);
  EXPECT_TRUE(median_band("one", {{{0, 1}, {3, 2}}}, "", true).band_low.empty());
  EXPECT_THROW(median_band("bad", {{{0, 1}, {3}}}, "", true), Error);
}

TEST(FieldPanels, OneRowOneColourRangeOneColourBar) {
  Grid2D a{0.5, 3.5, 0.5, 3.5, 4, 4, std::vector<double>(16, 1.0)};
  Grid2D b = a;
  for (int k = 0; k < 16; ++k) b.values[static_cast<std::size_t>(k)] = 10.0 * k / 15;
  FieldPanelsOptions options;
  options.value_label = "temperature";
  const std::string both = field_panels_svg({{"a", a}, {"b", b}}, options);
  EXPECT_TRUE(testing::SvgChecker::check(both).empty()) << both;
  const std::string svg = svg::layouts(both).wide;
  EXPECT_EQ(count(svg, "class=\"colorbar\""), 1u);
  EXPECT_NE(svg.find(">10<"), std::string::npos);  // the bar spans both panels' values
  // The constant panel a (all 1) is one path in the colour of 1 on the shared 0..10 scale
  // (shade 6 of 64), not in the middle of a range of its own.
  const ColorScale scale = ColorScale::of({&a, &b}, false, false);
  const std::size_t start = svg.find("<g shape-rendering=\"crispEdges\">");
  const std::string panel_a = svg.substr(start, svg.find("</g>", start) - start);
  EXPECT_EQ(count(panel_a, "<path"), 1u);
  EXPECT_NE(panel_a.find("fill=\"" + scale.color(6.5 / 64) + "\""), std::string::npos) << panel_a;
  EXPECT_NE(svg.find(">temperature<"), std::string::npos);
  // Signed fields: white at 0 in the middle of a symmetric range.
  const ColorScale signed_scale = ColorScale::of({&b}, false, true);
  EXPECT_DOUBLE_EQ(signed_scale.lo, -10);
  EXPECT_DOUBLE_EQ(signed_scale.unit(0), 0.5);
  EXPECT_THROW(field_panels_svg({}, options), Error);
}

TEST(SvgLandscape, EqualAspectWithAColourBar) {
  Grid2D grid{0, 2, 0, 1, 21, 11, {}};
  for (int j = 0; j < 11; ++j) {
    for (int i = 0; i < 21; ++i) grid.values.push_back(0.1 * i + j);
  }
  LandscapeOptions options;
  options.value_label = "L";
  options.title = "wide";
  const std::string both = landscape_svg(grid, {{"path", {0.1, 1.9}, {0.1, 0.9}, ""}}, options);
  EXPECT_TRUE(testing::SvgChecker::check(both).empty());
  const std::string svg = svg::layouts(both).wide;
  EXPECT_EQ(count(svg, "class=\"colorbar\""), 1u);
  // The clip rectangle is the plot box: twice as wide as high.
  const std::size_t clip = svg.find("<clipPath");
  const double w = std::stod(svg.substr(svg.find("width=\"", clip) + 7));
  const double h = std::stod(svg.substr(svg.find("height=\"", clip) + 8));
  EXPECT_NEAR(w, 2 * h, 1.0);
  options.equal_aspect = false;
  const std::string stretched = svg::layouts(landscape_svg(grid, {}, options)).wide;
  const std::size_t clip2 = stretched.find("<clipPath");
  EXPECT_GT(std::stod(stretched.substr(stretched.find("height=\"", clip2) + 8)), h + 50);
}

}  // namespace
}  // namespace physgrad
