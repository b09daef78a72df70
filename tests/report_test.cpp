// CSV tables written and read back, atomic file writes (whole or in pieces) and HTML pages:
// escaping, tables with captions, links and colours, figures, and the page written in parts.
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
#include "physgrad/report/page_spool.hpp"
#include "physgrad/report/line_plot.hpp"
#include "svg_check.hpp"

namespace physgrad {
namespace {

namespace fs = std::filesystem;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
using testing::count;


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

TEST_F(AtomicFile, PiecesMakeTheFileAndAProducerThatThrowsLeavesTheOldOne) {
  write_file_atomic(dir_ / "page.html", [](const ContentSink& sink) {
    sink("<p>");
    sink(std::string(100000, 'x'));  // larger than what is gathered into one write
    sink("</p>");
  });
  EXPECT_EQ(read(dir_ / "page.html"), "<p>" + std::string(100000, 'x') + "</p>");
  EXPECT_THROW(write_file_atomic(dir_ / "page.html",
                                 [](const ContentSink& sink) {
                                   sink("half");
                                   throw Error("the producer failed");
                                 }),
               Error);
  EXPECT_EQ(read(dir_ / "page.html"), "<p>" + std::string(100000, 'x') + "</p>");
  EXPECT_EQ(entries(), std::vector<std::string>{"page.html"});
}

TEST_F(AtomicFile, ASpoolGivesBackEachPartInTheOrderItWasWritten) {
  PageSpool::Part a, b;
  {
    PageSpool spool(dir_);
    spool.append(a, "a1 ");
    spool.append(b, "b1 ");
    spool.append(a, "a2 ");
    spool.append(a, std::string(70000, 'a'));  // copied back in blocks of 64 KiB
    spool.append(b, "b2");
    EXPECT_EQ(a.pieces.size(), 2u);  // "a2 " and the long one follow each other: one piece
    std::string text_a, text_b;
    std::size_t blocks = 0;
    spool.copy(a, [&](std::string_view piece) {
      text_a += piece;
      ++blocks;
    });
    spool.copy(b, [&](std::string_view piece) { text_b += piece; });
    EXPECT_EQ(text_a, "a1 a2 " + std::string(70000, 'a'));
    EXPECT_EQ(text_b, "b1 b2");
    EXPECT_GE(blocks, 3u);
    EXPECT_TRUE(entries().empty()) << "the spool file has a name";
  }
  EXPECT_TRUE(entries().empty());
  EXPECT_THROW(PageSpool(dir_ / "missing"), Error);
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

// html_report() is its parts written one after another, and a table's rows may be written in
// turns between its opening and its closing.
TEST(HtmlReport, ThePageInPartsIsThePageAtOnce) {
  const HtmlTable table{{"rule", "loss"}, {{"adam", "1"}, {"hig", "0.5"}}, "Losses", {}, {}};
  const HtmlSection section{"Results", "Text.", {table},
                            {{"A figure", line_plot_svg({{"s", {0, 1}, {1, 2}}}, {}), "f.svg"}},
                            {{"metrics.csv", "metrics.csv"}, {"index", "index.html", true}}};
  const std::string whole = html_report("Title", "Intro", {section});
  HtmlTable first = table, second = table;
  first.rows.pop_back();
  second.rows.erase(second.rows.begin());
  const std::string parts =
      html_page_open("Title", "Intro") + html_section_open(section) + html_table_open(table) +
      html_table_rows(first, "here") + html_table_rows(second, "here") +
      std::string(kHtmlTableClose) + html_figures(section.figures) +
      std::string(kHtmlSectionClose) + std::string(kHtmlPageClose);
  EXPECT_EQ(parts, whole);
  EXPECT_NE(whole.find("<p class=\"links\"><a href=\"./metrics.csv\">metrics.csv</a>"
                       "<a href=\"../index.html\">index</a></p>"),
            std::string::npos);
  HtmlTable ragged = table;
  ragged.rows[1].pop_back();
  EXPECT_THROW(html_table_rows(ragged, "here"), Error);
}

}  // namespace
}  // namespace physgrad
