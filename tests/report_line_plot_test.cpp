// Line plots: axes and ticks, non-finite and non-positive values, steps, legends placed where no
// data is, diverged series marked; series drawn over ones they would hide told apart ("coincides
// with", dashes and marker shapes of their own), series with nothing to draw saying why, hover
// titles on points, and the series hooks (<g class="series">, .line, .marker) a browser test
// reads. Every document is checked by the SVG checker.
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/run/cases/rule_colors.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/report/plot_marks.hpp"
#include "physgrad/report/svg_document.hpp"
#include "svg_check.hpp"

namespace physgrad {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
using testing::count;
using testing::has_non_finite_text;



// ----- line plot ------------------------------------------------------------------------------

TEST(SvgLinePlot, HasHeaderLegendLabelsAndTitle) {
  const std::vector<Series> series{{"gradient descent", {0, 1, 2}, {3, 2, 1}, color_for("gd")},
                                   {"Newton <fast>", {0, 1, 2}, {3, 1, 0.5}, "", true, true}};
  const std::string svg = line_plot_svg(series, {"Loss & more", "iteration", "loss"});
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("xmlns=\"http://www.w3.org/2000/svg\""), std::string::npos);
  EXPECT_NE(svg.find("viewBox=\"0 0 640 420\""), std::string::npos);
  EXPECT_NE(svg.find(">gradient descent<"), std::string::npos);
  EXPECT_NE(svg.find(">Newton &lt;fast&gt;<"), std::string::npos);
  EXPECT_NE(svg.find(">Loss &amp; more<"), std::string::npos);
  EXPECT_NE(svg.find("clipPath"), std::string::npos);
  EXPECT_NE(svg.find("stroke-dasharray"), std::string::npos);
  EXPECT_EQ(svg.substr(svg.size() - 7), "</svg>\n");
}

TEST(SvgLinePlot, NonFiniteValuesAreSkippedAndNonPositiveOnesSitOnTheLowerEdge) {
  const std::vector<Series> series{
      {"adam", {1, 2, 3, 4, 5, 6, 7}, {1, kNaN, 0.1, -1, 0.0, kInf, 1e-3}},
      {"all bad", {1, 2}, {kNaN, -kInf}}};
  LinePlotOptions options;
  options.log_y = true;
  const std::string svg = line_plot_svg(series, options);
  EXPECT_FALSE(has_non_finite_text(svg));
  EXPECT_NE(svg.find(">adam (≤ 0 from 4 ▼)<"), std::string::npos) << svg;
  options.log_x = true;
  EXPECT_FALSE(has_non_finite_text(line_plot_svg(series, options)));
}

TEST(SvgLinePlot, BrokenPointsSplitTheLine) {
  // Three finite runs separated by a NaN and an infinity: three subpaths.
  const std::vector<Series> series{{"s", {1, 2, 3, 4, 5, 6, 7}, {1, 2, kNaN, 3, 4, kInf, 5}}};
  LinePlotOptions options;
  options.log_y = true;
  const std::string svg = line_plot_svg(series, options);
  const auto start = svg.find("<g clip-path");
  const auto line = svg.find("<path d=\"", start);
  const auto end = svg.find('"', line + 9);
  EXPECT_EQ(count(svg.substr(line, end - line), "M"), 3u);
}

TEST(SvgLinePlot, LogAxisOverManyDecadesHasDecadeLabels) {
  Series s{"loss", {}, {}};
  for (int k = 0; k <= 80; ++k) {
    s.x.push_back(k);
    s.y.push_back(std::pow(10.0, -k / 10.0));
  }
  LinePlotOptions options;
  options.log_y = true;
  const std::string svg = line_plot_svg({s}, options);
  for (const char* label : {">1e-8<", ">1e-6<", ">1e-4<", ">0.01<", ">1<"}) {
    EXPECT_NE(svg.find(label), std::string::npos) << label;
  }
}

TEST(SvgLinePlot, LinearTicksAreNiceValues) {
  const std::string svg = line_plot_svg({{"s", {0, 10}, {0.13, 0.87}}}, {});
  for (const char* label : {">0.2<", ">0.4<", ">0.6<", ">0.8<", ">0<", ">10<"}) {
    EXPECT_NE(svg.find(label), std::string::npos) << label;
  }
}

TEST(SvgLinePlot, DegenerateInputsProduceFiniteOutput) {
  const std::vector<std::vector<Series>> cases{
      {},
      {{"empty", {}, {}}},
      {{"single", {3}, {7}}},
      {{"flat", {0, 1, 2}, {5, 5, 5}}},
      {{"zero", {1, 1}, {0, 0}}},
  };
  for (const auto& series : cases) {
    for (const bool log : {false, true}) {
      LinePlotOptions options;
      options.log_x = options.log_y = log;
      const std::string svg = line_plot_svg(series, options);
      EXPECT_EQ(svg.rfind("<svg", 0), 0u);
      EXPECT_FALSE(has_non_finite_text(svg)) << svg;
    }
  }
}

TEST(SvgLinePlot, InvalidInputThrows) {
  EXPECT_THROW(line_plot_svg({{"bad", {1, 2, 3}, {1, 2}}}, {}), Error);
  LinePlotOptions tiny;
  tiny.width = 10;
  EXPECT_THROW(line_plot_svg({}, tiny), Error);
}

TEST(SvgColor, EveryRuleHasTheCatalogueColourAndNoOtherRulesColour) {
  // A figure draws each rule in the catalogue's colour; distinct ids never share one (the same
  // id in both kinds, adam or gn, is one rule), and no Adam→rule twin, nor the control
  // Adam→Adam, takes a rule's colour.
  std::map<std::string, std::string> by_id;
  for (const RuleInfo& rule : rule_catalogue()) {
    EXPECT_EQ(color_for(rule.id), rule.colour) << rule.id;
    by_id[rule.id] = color_for(rule.id);
  }
  for (const std::string& id : rule_ids(RuleKind::kLearning)) {
    by_id[pretrained_run_id(id)] = color_for(pretrained_run_id(id));
  }
  EXPECT_EQ(by_id.count(pretrained_run_id(kPretrainingRule)), 1u);
  std::map<std::string, std::string> owner;
  for (const auto& [id, colour] : by_id) {
    const auto [it, fresh] = owner.emplace(colour, id);
    EXPECT_TRUE(fresh) << id << " and " << it->second << " share " << colour;
  }
  EXPECT_EQ(color_for("my-optimizer"), color_for("my-optimizer"));
  EXPECT_EQ(color_for("something else").size(), 7u);
}


TEST(SvgCheck, FindsMalformedDocumentsAndStrayCoordinates) {
  using testing::SvgChecker;
  const std::string head = "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 100 50\">";
  EXPECT_TRUE(SvgChecker::check(head + "<path d=\"M1 1L20 30h5v-2Z\"/><text x=\"3\" y=\"4\">a &amp; b</text></svg>").empty());
  for (const std::string& bad :
       {head + "<path d=\"M1 1 Lnan 2\"/></svg>", head + "<path d=\"M1 1 L200 2\"/></svg>",
        head + "<path d=\"M1 1 l99.5 60\"/></svg>", head + "<path d=\"L1 1\"/></svg>",
        head + "<path d=\"M1 1 C2 2 3 3 4 4\"/></svg>", head + "<path d=\"M1 1 L2\"/></svg>",
        head + "<g><path d=\"M1 1\"/></svg>", head + "<text x=\"1\" y=\"2\">a & b</text></svg>",
        head + "<rect x=\"inf\" y=\"0\" width=\"1\" height=\"1\"/></svg>",
        head + "<circle cx=\"-5\" cy=\"3\" r=\"1\"/></svg>", head + "<path d=M1/></svg>",
        std::string("<g></g>"), head + "</svg><svg viewBox=\"0 0 1 1\"></svg>"}) {
    EXPECT_FALSE(SvgChecker::check(bad).empty()) << bad;
  }
}

TEST(SvgLinePlot, EveryKindOfSeriesGivesValidSvgInsideItsViewBox) {
  Series band{"median", {0, 1, 2, 3}, {1, 0.5, 0.2, 0.1}, "", true};
  band.band_low = {0.5, 0.1, 1e-300, kNaN};
  band.band_high = {2, 1e300, 0.4, 0.3};
  Series steps{"steps", {0, 1, 2, 3}, {0.3, 0.6, 0.4, 0.4}};
  steps.steps = true;
  Series diverged{"diverged", {0, 1, 2, 3}, {1, 1e10, 1e300, kInf}};
  diverged.sets_range = false;
  Series zero{"zero", {0, 1, 2, 3}, {1, 0.1, 0, 0}};
  for (const bool log : {false, true}) {
    LinePlotOptions options;
    options.log_y = log;
    options.title = "all kinds";
    for (const auto& series : std::vector<std::vector<Series>>{
             {band, steps, diverged, zero}, {diverged}, {}, {{"one", {1}, {kNaN}}}}) {
      const std::string svg = line_plot_svg(series, options);
      const auto problems = testing::SvgChecker::check(svg);
      EXPECT_TRUE(problems.empty()) << problems.front() << "\n" << svg;
    }
  }
}

TEST(SvgLinePlot, DivergedSeriesIsMarkedAndDoesNotStretchTheAxis) {
  Series good{"converging", {0, 1, 2, 3}, {1, 0.1, 0.01, 0.001}};
  Series bad{"gd", {0, 1, 2, 3}, {1, 1e100, 1e300, kInf}};
  bad.sets_range = false;
  bad.end_label = "diverged at 3";
  LinePlotOptions options;
  options.log_y = true;
  const std::string svg = line_plot_svg({good, bad}, options);
  // It ends above the axis: an arrow at the frame with its last finite value.
  EXPECT_NE(svg.find(">diverged at 3, ends off scale at 1e+300<"), std::string::npos);
  EXPECT_NE(svg.find(">1<"), std::string::npos);  // the top decade of the converging series
  EXPECT_EQ(svg.find(">1e100<"), std::string::npos);
  EXPECT_EQ(svg.find(">1e300<"), std::string::npos);
  // Without a label, a series ending in a non-finite value still gets a mark.
  bad.end_label.clear();
  EXPECT_NE(line_plot_svg({good, bad}, options)
                .find(">not finite after x = 2, ends off scale at 1e+300<"),
            std::string::npos);
}

// ----- validity, divergence, zeros, legends ---------------------------------------------------

// The points of the first path after the clip group opens (the first series' line or band).
std::vector<std::pair<double, double>> first_path_points(const std::string& svg, std::size_t skip) {
  std::size_t at = svg.find("<g clip-path");
  for (std::size_t k = 0; k <= skip; ++k) at = svg.find("<path d=\"", at + 1);
  const std::string d = svg.substr(at + 9, svg.find('"', at + 9) - at - 9);
  std::vector<std::pair<double, double>> points;
  std::vector<double> numbers;
  std::string token;
  for (const char c : d + " ") {
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == '-') {
      token += c;
    } else if (!token.empty()) {
      numbers.push_back(std::stod(token));
      token.clear();
    }
  }
  for (std::size_t k = 0; k + 1 < numbers.size(); k += 2) points.emplace_back(numbers[k], numbers[k + 1]);
  return points;
}

// The legend's frame (x, y, width, height) when it sits inside the plot.
std::vector<double> legend_frame(const std::string& svg) {
  const std::size_t g = svg.find("<g class=\"legend\">");
  const std::size_t rect = svg.find("<rect", g);
  if (g == std::string::npos || rect != svg.find('<', g + 1)) return {};
  std::vector<double> frame;
  for (const char* key : {" x=\"", " y=\"", " width=\"", " height=\""}) {
    const std::size_t at = svg.find(key, rect) + std::string(key).size();
    frame.push_back(std::stod(svg.substr(at)));
  }
  return frame;
}

TEST(SvgLinePlot, ZeroOnALogAxisIsMarkedOnTheLowerEdge) {
  LinePlotOptions options;
  options.log_y = true;
  const std::string svg = line_plot_svg({{"lm", {0, 1, 2}, {1, 0.01, 0}}}, options);
  EXPECT_NE(svg.find("lm (0 from 2 ▼)"), std::string::npos) << svg;
  // The line reaches the lower edge of the frame: three points, the last on the bottom.
  const auto points = first_path_points(svg, 0);
  ASSERT_EQ(points.size(), 3u);
  EXPECT_DOUBLE_EQ(points[2].second, 420 - 52);  // the frame's bottom
}

TEST(SvgLinePlot, StepsHoldEachValueUntilTheNextX) {
  Series s{"cells", {0, 1, 2}, {1, 2, 2}};
  s.steps = true;
  const auto points = first_path_points(line_plot_svg({s}, {}), 0);
  ASSERT_EQ(points.size(), 5u);  // (0,1) (1,1) (1,2) (2,2) (2,2)
  EXPECT_EQ(points[0].second, points[1].second);
  EXPECT_EQ(points[1].first, points[2].first);
  EXPECT_EQ(points[2].second, points[3].second);
}

TEST(SvgLinePlot, LegendGoesWhereNoDataIsOrBelowThePlot) {
  // A U: high at both ends, low in the middle, so the top corners hold data.
  Series u{"u shape with a long label", {}, {}};
  for (int k = 0; k <= 40; ++k) {
    u.x.push_back(k);
    u.y.push_back((k - 20) * (k - 20));
  }
  const std::string svg = line_plot_svg({u}, {});
  const std::vector<double> frame = legend_frame(svg);
  ASSERT_EQ(frame.size(), 4u) << svg;
  const auto points = first_path_points(svg, 0);
  ASSERT_EQ(points.size(), 41u);
  for (std::size_t k = 1; k < points.size(); ++k) {
    for (double t = 0; t <= 1; t += 0.05) {
      const double x = points[k - 1].first + t * (points[k].first - points[k - 1].first);
      const double y = points[k - 1].second + t * (points[k].second - points[k - 1].second);
      EXPECT_FALSE(x >= frame[0] && x <= frame[0] + frame[2] && y >= frame[1] &&
                   y <= frame[1] + frame[3])
          << x << ", " << y;
    }
  }
  // Data everywhere: the legend moves below and the figure grows.
  Series zigzag{"zigzag", {}, {}};
  for (int k = 0; k <= 200; ++k) {
    zigzag.x.push_back(k);
    zigzag.y.push_back(k % 2);
  }
  const std::string full = line_plot_svg({zigzag}, {});
  EXPECT_TRUE(legend_frame(full).empty());
  EXPECT_EQ(full.find("viewBox=\"0 0 640 420\""), std::string::npos);
  EXPECT_NE(full.find(">zigzag<"), std::string::npos);
}

TEST(SvgLogAxis, NarrowRangesHaveSeveralLabels) {
  LinePlotOptions options;
  options.log_y = true;
  for (const auto& [lo, hi] : {std::pair{0.93, 0.99}, std::pair{0.55, 1.0}, std::pair{2e-5, 9e-5}}) {
    const std::string svg = line_plot_svg({{"s", {0, 1}, {lo, hi}}}, options);
    const std::size_t labels = count(svg, "text-anchor=\"end\"");
    EXPECT_GE(labels, 3u) << lo << " " << hi << "\n" << svg;
  }
}

// The group of the series labelled `label` (in the first layout).
std::string series_group(const std::string& svg, const std::string& label) {
  const std::size_t at = svg.find("<g class=\"series\" data-label=\"" + label + "\"");
  return at == std::string::npos ? "" : svg.substr(at, svg.find("</g>", at) - at);
}

// The value of attribute `name` of the path of class `element` in `text` ("" when none).
std::string attribute(const std::string& text, const std::string& element,
                      const std::string& name) {
  std::smatch m;
  const std::regex pattern("<path[^>]*class=\"" + element + "\"[^>]*" + name + "=\"([^\"]*)\"");
  return std::regex_search(text, m, pattern) ? m[1].str() : "";
}

// Series drawn over ones they would hide: B retraces A point for point, C lies along A's path
// (its points are a subset of A's, within a pixel), D is elsewhere. B and C get dash patterns
// and marker shapes none of those under them has, and say which they coincide with; D is left
// alone. Each series is one <g class="series"> with its line and markers.
TEST(SvgLinePlot, SeriesDrawnOverOnesTheyWouldHideAreToldApartAndSaySo) {
  std::vector<double> x, y;
  for (int k = 0; k <= 20; ++k) {
    x.push_back(k);
    y.push_back(10 - 0.4 * k);
  }
  std::vector<Series> series = {{"A", x, y, "#1f77b4", true}, {"B", x, y, "#ff7f0e", true},
                                {"C", {0, 10, 20}, {10, 6, 2}, "#2ca02c", true},
                                {"D", x, std::vector<double>(21, 9.0), "#d62728", true}};
  const std::string svg = line_plot_svg(series, {});
  for (const std::string& problem : testing::SvgChecker::check(svg)) ADD_FAILURE() << problem;
  const std::string a = series_group(svg, "A"), b = series_group(svg, "B"),
                    c = series_group(svg, "C"), d = series_group(svg, "D");
  ASSERT_FALSE(a.empty() || b.empty() || c.empty() || d.empty()) << svg;
  EXPECT_EQ(attribute(a, "line", "stroke-dasharray"), "");
  EXPECT_NE(attribute(b, "line", "stroke-dasharray"), "");
  EXPECT_NE(attribute(c, "line", "stroke-dasharray"), attribute(b, "line", "stroke-dasharray"));
  EXPECT_EQ(attribute(d, "line", "stroke-dasharray"), "");
  EXPECT_EQ(attribute(a, "marker", "data-shape"), "0");
  EXPECT_NE(attribute(b, "marker", "data-shape"), "0");
  EXPECT_NE(attribute(c, "marker", "data-shape"), attribute(b, "marker", "data-shape"));
  EXPECT_NE(svg.find(">B (coincides with A)<"), std::string::npos);
  EXPECT_NE(svg.find(">C (coincides with A, B)<"), std::string::npos);
  EXPECT_NE(svg.find(">D<"), std::string::npos);
  // Half a pixel apart is still drawn over; a few pixels apart is not.
  series[1].y = y;
  for (double& v : series[1].y) v += 0.001;
  series[3].y = y;
  for (double& v : series[3].y) v += 0.5;
  const std::string near = line_plot_svg(series, {});
  EXPECT_NE(near.find(">B (coincides with A)<"), std::string::npos);
  EXPECT_NE(near.find(">D<"), std::string::npos);
}

// A series with no point to draw is not silently missing: its group says why (data-empty) and
// so does its legend entry, with the end label it was given.
TEST(SvgLinePlot, ASeriesWithNothingToDrawSaysWhy) {
  Series never{"GD", {1, 10, 100}, {kNaN, kNaN, kNaN}, "#1f77b4", true};
  never.end_label = "α = 1: > 200";
  const std::string svg =
      line_plot_svg({never, {"Newton", {1, 10, 100}, {10, 10, 10}}, {"empty", {}, {}}}, {});
  EXPECT_NE(svg.find("<g class=\"series\" data-label=\"GD\" data-empty=\"α = 1: &gt; 200\">"),
            std::string::npos);
  EXPECT_NE(svg.find(">GD (not drawn: α = 1: &gt; 200)<"), std::string::npos);
  EXPECT_NE(svg.find(">empty (not drawn: no finite value)<"), std::string::npos);
  EXPECT_EQ(svg.find("data-label=\"Newton\" data-empty"), std::string::npos);
}

// Every point shows its values on hover (an SVG <title>, no script), the label escaped.
TEST(SvgLinePlot, PointsShowTheirValuesOnHover) {
  std::vector<double> x, y;
  for (int k = 0; k < 600; ++k) {
    x.push_back(k);
    y.push_back(1.0 / (1 + k));
  }
  LinePlotOptions options;
  options.x_label = "iteration";
  options.y_label = "loss";
  options.narrow = false;
  const std::string svg =
      line_plot_svg({{"a<b", {1, 2, 3}, {0.5, 0.25, 0.125}}, {"long", x, y}}, options);
  EXPECT_NE(svg.find("<title>a&lt;b: iteration = 2, loss = 0.25</title>"), std::string::npos);
  EXPECT_EQ(count(svg, "<title>a&lt;b: "), 3u);
  EXPECT_EQ(count(svg, "<title>long: "), 600u);
  EXPECT_NE(svg.find("<title>long: iteration = 0, loss = 1</title>"), std::string::npos);
  EXPECT_EQ(plot::short_number(1.0 / 3), "0.3333");
}

}  // namespace
}  // namespace physgrad
