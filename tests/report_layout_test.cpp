// Numbers with the digits their spread supports (significant.hpp); figures in two layouts:
// responsive() documents, their layouts, panels side by side that stack in the narrow one, the
// width below which a page shows the narrow one, and the figures of an HTML page switching there;
// the marker shapes that tell series apart.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <limits>
#include <string>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/report/html_report.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/report/plot_marks.hpp"
#include "physgrad/report/significant.hpp"
#include "physgrad/report/svg_document.hpp"
#include "svg_check.hpp"

namespace physgrad {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(Significant, SpreadIsTheMedianAndRangeOfTheFiniteValues) {
  const Spread s = spread_of({3, kNaN, 1, 2, INFINITY, 10});
  EXPECT_EQ(s.count, 4u);
  EXPECT_EQ(s.median, 2.5);
  EXPECT_EQ(s.low, 1);
  EXPECT_EQ(s.high, 10);
  const Spread none = spread_of({kNaN});
  EXPECT_EQ(none.count, 0u);
  EXPECT_TRUE(std::isnan(none.median));
  EXPECT_EQ(median_and_range(none), "–");
}

// d = ⌊log₁₀|m|⌋ − ⌊log₁₀(max − min)⌋ + 2: the range resolved to two digits.
TEST(Significant, DigitsResolveTheRangeToTwoDigits) {
  EXPECT_EQ(digits_for(spread_of({0.0118, 0.0123, 0.0131})), 3);
  EXPECT_EQ(median_and_range(spread_of({0.0118, 0.0123, 0.0131})), "0.0123 (0.0118–0.0131)");
  EXPECT_EQ(digits_for(spread_of({0.4, 0.5, 0.6})), 2);  // −1 − (−1) + 2
  EXPECT_EQ(digits_for(spread_of({1.0001, 1.0002})), 6);  // clamped at 6
  EXPECT_EQ(digits_for(spread_of({0.01, 0.02, 100})), 1);  // clamped at 1
  // One seed, or all alike: two digits and no range.
  EXPECT_EQ(digits_for(spread_of({0.123456})), 2);
  EXPECT_EQ(median_and_range(spread_of({0.123456})), "0.12");
  EXPECT_EQ(median_and_range(spread_of({0.5, 0.5})), "0.50");  // the zero is a digit shown
}

TEST(Significant, WholeNumbersInFullOthersRounded) {
  EXPECT_EQ(with_digits(239.5, 2), "240");  // not 2.4e+02
  EXPECT_EQ(with_digits(545.5, 2), "550");
  EXPECT_EQ(with_digits(1234, 2), "1234");  // a count stays as it is
  EXPECT_EQ(with_digits(0.012345, 3), "0.0123");
  EXPECT_EQ(with_digits(2.5e7, 2), "25000000");
  EXPECT_EQ(with_digits(3.6e-05, 1), "4e-05");  // not "4.e-05"
  EXPECT_EQ(with_digits(0.00018, 1), "0.0002");
  EXPECT_EQ(with_digits(3.6e-05, 2), "3.6e-05");
  EXPECT_EQ(with_digits(25340000.5, 2), "2.5e+07");
  EXPECT_EQ(with_digits(kNaN, 2), "–");
  EXPECT_EQ(with_digits(-INFINITY, 2), "-inf");
  EXPECT_EQ(median_and_range(spread_of({10, 20, 30})), "20 (10–30)");
}

// A ratio of medians carries the digits the wider relative spread allows: three between values
// that vary by 3 %, one between values that vary tenfold, two from one seed each.
TEST(Significant, RatiosCarryTheDigitsTheirSpreadsAllow) {
  const Spread a = spread_of({1.00, 1.012, 1.03}), b = spread_of({0.99, 1.0, 1.01});
  EXPECT_EQ(ratio_digits(a, b), 3);  // relative spread 0.03: ⌊1.52⌋ + 2
  EXPECT_EQ(ratio_text(a, b), "1.01");
  const Spread wide = spread_of({0.5, 1.0, 1.5});
  EXPECT_EQ(ratio_digits(wide, b), 2);  // relative spread 1: 0 + 2
  EXPECT_EQ(ratio_digits(spread_of({0.2, 2.0, 20.0}), b), 1);
  EXPECT_EQ(ratio_text(spread_of({3.0}), spread_of({1.3})), "2.3");
  EXPECT_EQ(ratio_text(spread_of({6.0}), spread_of({2.0})), "3");
  EXPECT_EQ(ratio_text(spread_of({0.5113}), spread_of({0.5108})), "1.0");
}

// A wide document (640 × 420) and a narrow one (380 × 500) as one responsive document: both
// layouts kept and given back, the wide one shown without CSS, the narrow one below 640 px.
TEST(ResponsiveSvg, TwoLayoutsInOneDocument) {
  const std::string wide = svg::open(640, 420) + "<text x=\"1\" y=\"2\">wide</text>\n</svg>\n";
  const std::string narrow = svg::open(380, 500) + "<text x=\"1\" y=\"2\">narrow</text>\n</svg>\n";
  const std::string both = svg::responsive(wide, narrow);
  for (const std::string& problem : testing::SvgChecker::check(both)) ADD_FAILURE() << problem;
  EXPECT_EQ(svg::size_of(both), std::make_pair(640, 420));
  const svg::Layouts layouts = svg::layouts(both);
  EXPECT_EQ(layouts.wide, wide);
  EXPECT_EQ(layouts.narrow, narrow);
  EXPECT_NE(both.find("<svg class=\"pg-narrow\" display=\"none\""), std::string::npos);
  EXPECT_NE(both.find("@media (max-width:639px)"), std::string::npos);
  // Sized by the narrow layout, its shape kept where a page sizes the figure by its width.
  EXPECT_NE(both.find("{width:380px;height:500px;aspect-ratio:380/500}"), std::string::npos);
  // A page with margins moves that width; a document of one layout is left as it is.
  const std::string moved = svg::switched_below(both, 700);
  EXPECT_NE(moved.find("@media (max-width:699px)"), std::string::npos);
  EXPECT_EQ(moved.find("@media (max-width:639px)"), std::string::npos);
  EXPECT_EQ(svg::layouts(moved).narrow, narrow);
  EXPECT_EQ(svg::switched_below(wide, 700), wide);
  EXPECT_EQ(svg::layouts(wide).narrow, wide);
  EXPECT_THROW(svg::responsive("<svg>", narrow), Error);
}

// Panels side by side in the wide layout are stacked in the narrow one, each in its own narrow
// layout, 12 px apart.
TEST(ResponsiveSvg, PanelsSideBySideStackWhenNarrow) {
  Series s{"s", {0, 1, 2}, {1, 2, 1}};
  const std::string panel = line_plot_svg({s}, {});
  const auto [nw, nh] = svg::size_of(svg::layouts(panel).narrow);
  EXPECT_EQ(nw, svg::kNarrowWidth);
  const std::string row = svg::side_by_side({panel, panel});
  for (const std::string& problem : testing::SvgChecker::check(row)) ADD_FAILURE() << problem;
  EXPECT_EQ(svg::size_of(row).first, 2 * 640 + 12);
  EXPECT_EQ(svg::size_of(svg::layouts(row).narrow), std::make_pair(nw, 2 * nh + 12));
  // Small documents side by side that fit a phone keep one layout.
  const std::string small = svg::open(180, 100) + "</svg>\n";
  EXPECT_EQ(svg::layouts(svg::side_by_side({small, small})).narrow,
            svg::side_by_side({small, small}));
}

// A grid places its rows side by side, one row above the next, and stacks all its panels in
// reading order when narrow.
TEST(ResponsiveSvg, GridRowsStackAndAllPanelsStackWhenNarrow) {
  const std::string panel = line_plot_svg({{"s", {0, 1, 2}, {1, 2, 1}}}, {});
  const auto [nw, nh] = svg::size_of(svg::layouts(panel).narrow);
  const auto [pw, ph] = svg::size_of(panel);
  const std::string grid = svg::grid({{panel, panel}, {panel, panel}});
  for (const std::string& problem : testing::SvgChecker::check(grid)) ADD_FAILURE() << problem;
  EXPECT_EQ(svg::size_of(grid), std::make_pair(2 * pw + 12, 2 * ph + 12));
  EXPECT_EQ(svg::size_of(svg::layouts(grid).narrow), std::make_pair(nw, 4 * nh + 3 * 12));
  EXPECT_EQ(svg::grid({{panel, panel}}), svg::side_by_side({panel, panel}));
}

// In a page, a figure switches to its narrow layout below the width at which its wide layout's
// smallest text (12 px in a 640 px figure) would be 11 px — ⌈640 · 11 / 12⌉ = 587 px — plus the
// page's margins (42 px); above that the wide one scales with the page.
TEST(ResponsiveSvg, APageSwitchesWhereTheWideTextWouldFallBelowElevenPixels) {
  const std::string figure = line_plot_svg({{"s", {0, 1}, {1, 2}}}, {});
  const std::string html = html_figures({{"caption", figure}});
  EXPECT_NE(html.find("@media (max-width:628px)"), std::string::npos);
  EXPECT_EQ(html.find("@media (max-width:639px)"), std::string::npos);
  // The narrow layout (380 px) is kept from shrinking below 11 px text: 349 px.
  EXPECT_NE(html.find("<div style=\"min-width:349px\">"), std::string::npos);
}

// The marker shapes: a dot, □, △, ◇, ▽, each a path of its own kind.
TEST(SvgMarks, FiveShapesCycled) {
  const svg::Point p{100, 50};
  EXPECT_EQ(plot::marker_path(0, p, 7), svg::dot(p));
  EXPECT_EQ(plot::marker_path(1, p, 7), "M96.5 46.5h7v7h-7Z");
  EXPECT_EQ(plot::marker_path(1 + plot::kShapes, p, 7), plot::marker_path(1, p, 7));
  std::set<std::string> shapes;
  for (int k = 0; k < plot::kShapes; ++k) shapes.insert(plot::marker_path(k, p, 7));
  EXPECT_EQ(shapes.size(), static_cast<std::size_t>(plot::kShapes));
  const std::string markers =
      plot::markers_svg({{p, {110, 60}, {120, 70}}}, {0, 0, 200, 200}, 2, 7, "#000000");
  EXPECT_NE(markers.find("class=\"marker\" data-shape=\"2\""), std::string::npos);
  EXPECT_EQ(std::count(markers.begin(), markers.end(), 'Z'), 3);  // three triangles
}

}  // namespace
}  // namespace physgrad
