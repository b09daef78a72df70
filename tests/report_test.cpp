#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/io/atomic_file.hpp"
#include "physgrad/io/csv.hpp"
#include "physgrad/report/html_report.hpp"
#include "physgrad/report/colors.hpp"
#include "physgrad/report/field_plot.hpp"
#include "physgrad/report/isolines.hpp"
#include "physgrad/report/landscape.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/report/svg_document.hpp"
#include "physgrad/report/seed_band.hpp"
#include "svg_check.hpp"

namespace physgrad {
namespace {


namespace fs = std::filesystem;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::size_t count(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto pos = text.find(needle); pos != std::string::npos; pos = text.find(needle, pos + 1))
    ++n;
  return n;
}

// True when the text contains "nan" or "inf" in any letter case.
bool has_non_finite_text(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text.find("nan") != std::string::npos || text.find("inf") != std::string::npos;
}

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, sep);) parts.push_back(part);
  return parts;
}

// A fresh empty directory, removed at the end of the test.
class AtomicFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("physgrad_report_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_))
      names.push_back(e.path().filename().string());
    return names;
  }

  fs::path dir_;
};

std::string read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}


// ----- CSV ------------------------------------------------------------------------------------

TEST(Csv, QuotesFieldsWithCommaQuoteOrNewline) {
  CsvTable table({"name", "note"});
  table.add_row({std::string("plain"), std::string("a,b")});
  table.add_row({std::string("say \"hi\""), std::string("two\nlines")});
  EXPECT_EQ(table.rows(), 2u);
  EXPECT_EQ(table.str(), "name,note\nplain,\"a,b\"\n\"say \"\"hi\"\"\",\"two\nlines\"\n");
}

TEST(Csv, DoublesRoundTripBitExact) {
  const std::vector<double> values{0.1,
                                   -1.0 / 3.0,
                                   6.02214076e23,
                                   std::acos(-1.0),
                                   1e300,
                                   -0.0,
                                   std::nextafter(1.0, 2.0),
                                   std::numeric_limits<double>::max(),
                                   std::numeric_limits<double>::min(),
                                   123456789.123456789};
  CsvTable table({"v"});
  for (const double v : values) table.add_row({v});
  const std::vector<std::string> lines = split(table.str(), '\n');
  ASSERT_EQ(lines.size(), values.size() + 1);
  for (std::size_t k = 0; k < values.size(); ++k) {
    EXPECT_EQ(std::bit_cast<std::uint64_t>(std::stod(lines[k + 1])),
              std::bit_cast<std::uint64_t>(values[k]))
        << lines[k + 1];
  }
}

TEST(Csv, ParsesWhatItWritesAndRefusesRaggedRows) {
  CsvTable table({"label", "x", "note"});
  table.add_row({std::string("a,b"), 0.1, std::string("say \"hi\"\nagain")});
  table.add_row({std::string(""), 3LL, std::string("plain")});
  const CsvData data = parse_csv(table.str());
  EXPECT_EQ(data.columns, (std::vector<std::string>{"label", "x", "note"}));
  ASSERT_EQ(data.rows.size(), 2u);
  EXPECT_EQ(data.rows[0], (std::vector<std::string>{"a,b", "0.1", "say \"hi\"\nagain"}));
  EXPECT_EQ(data.rows[1], (std::vector<std::string>{"", "3", "plain"}));
  EXPECT_EQ(data.column("note"), 2u);
  EXPECT_EQ(data.column("missing"), 3u);
  EXPECT_EQ(parse_csv("a,b\r\n1,2").rows.size(), 1u);
  EXPECT_THROW(parse_csv("a,b\n1,2,3\n"), Error);
  EXPECT_THROW(parse_csv("a,b\n\"1,2\n"), Error);
}

TEST(Csv, KeepsTheSelectedColumnsOfTheFirstRowsAndBoundsTheHeader) {
  const std::string text = "a,b,c\n1,2,3\n4,5,6\n7,8,9\n";
  const CsvData data = parse_csv(text, {{"c", "a", "missing"}, 2});
  EXPECT_EQ(data.columns, (std::vector<std::string>{"a", "c"}));
  EXPECT_EQ(data.rows, (std::vector<std::vector<std::string>>{{"1", "3"}, {"4", "6"}}));
  EXPECT_EQ(data.rows_left_out, 1u);
  EXPECT_EQ(parse_csv(text).rows_left_out, 0u);
  // The rows not kept are still checked.
  EXPECT_THROW(parse_csv(text + "1,2\n", {{}, 1}), Error);
  // A header of many cells is counted, not kept: a line of 10^6 commas is refused at once.
  try {
    parse_csv(std::string(1000000, ','), {{"a"}, 10, 4096});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "csv: the header has 1000001 cells, more than the 4096 read");
  }
  EXPECT_EQ(parse_csv(std::string(4095, ','), {{}, 10, 4096}).columns.size(), 4096u);
}

TEST(Csv, IntegersAndNonFiniteDoubles) {
  CsvTable table({"i", "a", "b", "c"});
  table.add_row({-42LL, kNaN, kInf, -kInf});
  EXPECT_EQ(table.str(), "i,a,b,c\n-42,nan,inf,-inf\n");
}

TEST(Csv, RowSizeMismatchThrowsNamingBothCounts) {
  CsvTable table({"a", "b", "c"});
  try {
    table.add_row({1.0, 2.0});
    FAIL() << "no Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find('2'), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find('3'), std::string::npos) << e.what();
  }
  EXPECT_EQ(table.rows(), 0u);
}

// ----- atomic file ----------------------------------------------------------------------------

TEST_F(AtomicFile, CreatesFileWithExactContent) {
  const std::string content =
      std::string("line one\nbinary \0 byte\n", 23) + std::string(100000, 'x');
  write_file_atomic(dir_ / "out.txt", content);
  EXPECT_EQ(read(dir_ / "out.txt"), content);
  EXPECT_EQ(entries(), std::vector<std::string>{"out.txt"});
}

TEST_F(AtomicFile, OverwritesExistingFileAndLeavesNoTempFiles) {
  write_file_atomic(dir_ / "out.txt", "a much longer first version");
  write_file_atomic(dir_ / "out.txt", "second");
  EXPECT_EQ(read(dir_ / "out.txt"), "second");
  write_file_atomic(dir_ / "empty.txt", "");
  EXPECT_EQ(read(dir_ / "empty.txt"), "");
  const std::vector<std::string> names = entries();
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()),
            (std::set<std::string>{"out.txt", "empty.txt"}));
}

TEST_F(AtomicFile, MissingDirectoryThrowsAndCreatesNothing) {
  const fs::path target = dir_ / "missing" / "out.txt";
  try {
    write_file_atomic(target, "content");
    FAIL() << "no Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(target.string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "missing"));
  EXPECT_TRUE(entries().empty());
}

TEST_F(AtomicFile, TargetThatIsADirectoryThrowsAndCleansUp) {
  fs::create_directory(dir_ / "taken");
  EXPECT_THROW(write_file_atomic(dir_ / "taken", "content"), Error);
  EXPECT_EQ(entries(), std::vector<std::string>{"taken"});
}

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

TEST(SvgColor, FixedColoursForOptimizerIdsAndStableHashForOthers) {
  const std::vector<std::string> ids{"gd", "momentum", "adam", "newton", "bfgs", "lbfgs", "gn",
                                     "lm", "ig",       "pg",   "sgd",    "hig",  "sip"};
  std::set<std::string> colors;
  for (const auto& id : ids) colors.insert(color_for(id));
  EXPECT_EQ(colors.size(), ids.size());
  EXPECT_EQ(color_for("my-optimizer"), color_for("my-optimizer"));
  for (const auto& c : {color_for("adam"), color_for("something else")}) {
    EXPECT_EQ(c.size(), 7u);
    EXPECT_EQ(c[0], '#');
  }
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

TEST(HtmlReport, EscapesTextAndEmbedsFiguresAndTables) {
  const std::string svg = line_plot_svg({{"s", {0, 1}, {0, 1}}}, {});
  HtmlSection section{"Results <1>",
                      "First <script>alert(1)</script> paragraph.\n\nSecond & last.",
                      {{{"optimizer", "loss"}, {{"adam", "1e-3"}, {"newton", "<0.1>"}}}},
                      {{"Loss curves", svg}, {"Again", svg}}};
  const std::string html = html_report("Report \"A\"", "Intro", {section});
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("<meta charset=\"utf-8\">"), std::string::npos);
  EXPECT_EQ(html.find("<script>"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos);
  EXPECT_NE(html.find("<p>Second &amp; last.</p>"), std::string::npos);
  EXPECT_NE(html.find("Report &quot;A&quot;"), std::string::npos);
  // Both figures, each as drawn (its <style> may move the width its narrow layout takes over).
  EXPECT_EQ(count(html, svg.substr(svg.find("</style>"))), 2u);
  for (const char* cell :
       {">optimizer<", ">loss<", ">adam<", ">1e-3<", ">newton<", ">&lt;0.1&gt;<"}) {
    EXPECT_NE(html.find(cell), std::string::npos) << cell;
  }
  EXPECT_NE(html.find(">Loss curves</figcaption>"), std::string::npos);
}

TEST(HtmlReport, CaptionsAboveScrollBoxesLinksAndFigureAnchors) {
  HtmlTable table{{"run", "loss"}, {{"a", "1"}, {"b", "2"}}, "Losses <test set>",
                  {{"a/report.html", ""}, {"", ""}}};
  const HtmlSection section{"S", "", {table}, {{"Caption", "<svg></svg>", "loss.svg"}}};
  const std::string html = html_report("T", "", {section});
  const std::size_t caption = html.find("<p class=\"caption\">Losses &lt;test set&gt;</p>");
  ASSERT_NE(caption, std::string::npos) << html;
  EXPECT_LT(caption, html.find("<div class=\"table\"><table>"));
  EXPECT_NE(html.find("<td data-h=\"run\"><a href=\"./a/report.html\">a</a></td>"),
            std::string::npos);
  EXPECT_NE(html.find("<td data-h=\"run\">b</td>"), std::string::npos);
  EXPECT_NE(html.find("<figure id=\"loss.svg\">"), std::string::npos);
  EXPECT_NE(html.find("overflow-x:auto"), std::string::npos);
  table.links = {{"x", ""}};  // one row of links for two rows
  EXPECT_THROW(html_report("T", "", {{"S", "", {table}, {}}}), Error);
  table.links = {{"x"}, {"", ""}};  // a row of links of the wrong length
  EXPECT_THROW(html_report("T", "", {{"S", "", {table}, {}}}), Error);
  table.links = {{"../up", ""}, {"", ""}};  // a link out of the page's folder
  EXPECT_THROW(html_report("T", "", {{"S", "", {table}, {}}}), Error);
}

TEST(HtmlReport, LinksArePercentEncodedPathsInsideThePagesFolder) {
  EXPECT_EQ(local_href("a/report.html"), "./a/report.html");
  EXPECT_EQ(local_href("javascript:void(alert(1))/report.html"),
            "./javascript%3Avoid%28alert%281%29%29/report.html");
  EXPECT_EQ(local_href("http:127.0.0.1:9"), "./http%3A127.0.0.1%3A9");
  EXPECT_EQ(local_href("a#b?c%41 d/x"), "./a%23b%3Fc%2541%20d/x");
  EXPECT_EQ(local_href("Az09-._~"), "./Az09-._~");
  EXPECT_EQ(local_href("\xff\\\"'<&/\xce\xbb"), "./%FF%5C%22%27%3C%26/%CE%BB");
  EXPECT_EQ(local_href("..a/.b"), "./..a/.b");
  for (const char* outside :
       {"", "/etc/passwd", "a//b", "a/", "..", "../x", "a/../../x", ".", "./a"}) {
    EXPECT_THROW(local_href(outside), Error) << outside;
  }
}

TEST(HtmlReport, RaggedTableRowThrows) {
  const HtmlSection section{"S", "", {{{"a", "b"}, {{"1"}}}}, {}};
  EXPECT_THROW(html_report("T", "", {section}), Error);
}

}  // namespace
}  // namespace physgrad
