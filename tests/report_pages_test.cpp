// Every experiment's report, rendered at tiny sizes through the command line, and the index of
// their folders (`physgrad report`): each SVG file and each SVG inside report.html and
// index.html is well-formed, with finite coordinates inside its view box; the figures that carry
// each experiment's message exist, and each report opens with the message figure that
// docs/results.md names; every table has a caption; a report links its files and the index and
// says when, by which version, with which command and options it ran.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "report_pages_fixture.hpp"
#include "svg_check.hpp"

namespace {

using physgrad::testing::Case;
using physgrad::testing::cases;
using physgrad::testing::count;
using physgrad::testing::inline_svgs;
using physgrad::testing::link_attributes;
using physgrad::testing::read_file;
using physgrad::testing::ReportPages;
using physgrad::testing::SvgChecker;
namespace fs = std::filesystem;

TEST_F(ReportPages, EverySvgIsWellFormedAndInsideItsViewBox) {
  ASSERT_TRUE(make_reports());
  std::size_t checked = 0;
  const auto check = [&](const std::string& svg, const std::string& where) {
    for (const std::string& problem : SvgChecker::check(svg)) ADD_FAILURE() << where << ": " << problem;
    ++checked;
  };
  for (const Case& c : cases()) {
    const fs::path folder = dir_ / c.folder;
    for (const std::string& figure : c.figures) {
      EXPECT_TRUE(fs::exists(folder / figure)) << c.folder << " lacks " << figure;
    }
    std::size_t files = 0;
    for (const auto& entry : fs::directory_iterator(folder)) {
      if (entry.path().extension() != ".svg") continue;
      check(read_file(entry.path()), entry.path().string());
      ++files;
    }
    const std::string html = read_file(folder / "report.html");
    const std::vector<std::string> svgs = inline_svgs(html);
    EXPECT_EQ(svgs.size(), files) << c.folder;
    for (const std::string& svg : svgs) check(svg, c.folder + "/report.html");
    // Every table has a caption above it.
    EXPECT_EQ(count(html, "<p class=\"caption\">"), count(html, "<table>")) << c.folder;
  }
  // The messages: seeds as median and band; diverged GD marked, the axis left to the others.
  const std::string seeds = read_file(dir_ / "hig-toy" / "loss_vs_time_lambda_0.01.svg");
  EXPECT_NE(seeds.find("HIG (λ=0.01), median of 2"), std::string::npos);
  EXPECT_NE(seeds.find("fill-opacity=\"0.18\""), std::string::npos);
  const std::string diverged = read_file(dir_ / "scaled-toy" / "loss_alpha_100.svg");
  EXPECT_NE(diverged.find(">diverged at 77, ends off scale at "), std::string::npos);
  for (const char* label : {">1e10<", ">1e100<", ">1e300<"}) {
    EXPECT_EQ(diverged.find(label), std::string::npos) << label;
  }
  const std::string index = read_file(dir_ / "index.html");
  EXPECT_NE(index.find("href=\"./hig-toy/report.html\""), std::string::npos);
  const std::vector<std::string> overlays = inline_svgs(index);
  EXPECT_GE(overlays.size(), 6u);  // one per learning experiment
  for (const std::string& svg : overlays) check(svg, "index.html");
  EXPECT_GT(checked, 60u);
}

// Experiment name → its message figure, as docs/results.md names it: the line
// "Message figure: `FILE`" in the section "## NAME — `physgrad run NAME …`".
std::map<std::string, std::string> documented_messages() {
  const std::string text = read_file(fs::path(PHYSGRAD_SOURCE_DIR) / "docs" / "results.md");
  static const std::regex heading(R"(^## ([a-z0-9-]+) — )");
  static const std::regex message(R"(^Message figure: `([^`]+)`)");
  std::map<std::string, std::string> found;
  std::string section;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    if (std::regex_search(line, m, heading)) section = m[1];
    if (std::regex_search(line, m, message) && !section.empty()) found[section] = m[1];
  }
  return found;
}

// The experiment a case runs: the word after "run ".
std::string experiment_of(const Case& c) {
  const std::string rest = c.args.substr(4);
  return rest.substr(0, rest.find(' '));
}

TEST_F(ReportPages, EachReportOpensWithTheMessageFigureTheResultsDocumentNames) {
  ASSERT_TRUE(make_reports());
  const std::map<std::string, std::string> messages = documented_messages();
  std::size_t checked = 0;
  for (const Case& c : cases()) {
    const std::string name = experiment_of(c);
    ASSERT_TRUE(messages.contains(name)) << "docs/results.md names no message figure of " << name;
    if (c.folder != name) continue;  // a variant (e.g. 1-D) names its files differently
    const std::string html = read_file(dir_ / c.folder / "report.html");
    const std::size_t first = html.find("<figure");
    ASSERT_NE(first, std::string::npos) << c.folder;
    EXPECT_EQ(html.substr(first, html.find('>', first) - first),
              "<figure id=\"" + messages.at(name) + "\"")
        << c.folder;
    // The sentence under it, with a ratio or the numbers it compares.
    const std::size_t sentence = html.find("<p class=\"message\">", first);
    ASSERT_NE(sentence, std::string::npos) << c.folder;
    EXPECT_LT(sentence, html.find("</figure>", first)) << c.folder;
    const std::string text = html.substr(sentence, html.find("</p>", sentence) - sentence);
    EXPECT_NE(text.find_first_of("0123456789"), std::string::npos) << c.folder << ": " << text;
    ++checked;
  }
  EXPECT_EQ(checked + 1, cases().size());  // all but the 1-D variant
  EXPECT_EQ(messages.size(), checked);    // and no documented experiment without a case
}

// "2026-11-27 08:40 UTC" for a time point, as the reports write it.
std::string utc_minute(std::chrono::system_clock::time_point at) {
  const std::time_t t = std::chrono::system_clock::to_time_t(at);
  std::tm utc{};
  ::gmtime_r(&t, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", &utc);
  return text;
}

TEST_F(ReportPages, AReportLinksItsFilesAndSaysWhenAndHowItRan) {
  const auto start = std::chrono::system_clock::now();
  ASSERT_EQ(run("run comparison --iters 3 --out runs/direct").exit_code, 0);
  ASSERT_EQ(run("run hig-toy --seeds 1 --iters 4 --eval-every 2 --train-size 8 --test-size 4 "
                "--lambda 0.01 --out runs/learning")
                .exit_code,
            0);
  ASSERT_EQ(run("report runs").exit_code, 0);
  const auto end = std::chrono::system_clock::now();
  for (const std::string folder : {"direct", "learning"}) {
    const std::string html = read_file(dir_ / "runs" / folder / "report.html");
    // Links to the folder's files, each a file that is there (the index above it was written
    // after the reports: no link to it).
    std::vector<std::string> files = {"./metrics.csv", "./summary.json", "./config.json"};
    if (folder == "learning") files.push_back("./networks.json");
    const std::vector<std::string> links = link_attributes(html);
    for (const std::string& file : files) {
      EXPECT_NE(std::find(links.begin(), links.end(), file), links.end()) << folder << ": " << file;
      EXPECT_TRUE(fs::is_regular_file(dir_ / "runs" / folder / file)) << folder << ": " << file;
    }
    // When (the minute the report was written), by which version, with which command.
    std::smatch written;
    ASSERT_TRUE(std::regex_search(
        html, written, std::regex(R"(Written (\d{4}-\d\d-\d\d \d\d:\d\d UTC) by physgrad (\d+\.\d+\.\d+) \(commit )")))
        << folder;
    EXPECT_GE(written[1].str(), utc_minute(start)) << folder;
    EXPECT_LE(written[1].str(), utc_minute(end)) << folder;
    EXPECT_NE(html.find("<p>Command as typed: " + std::string(PHYSGRAD_CLI) + " run "), std::string::npos)
        << folder;
    EXPECT_NE(html.find("--out runs/" + folder + "</p>"), std::string::npos) << folder;
  }
  // Every option with the value the run had and its default.
  const std::string direct = read_file(dir_ / "runs" / "direct" / "report.html");
  EXPECT_NE(direct.find("<tr><td data-h=\"option\">--iters</td><td data-h=\"value\">3</td>"
                        "<td data-h=\"default\">10</td></tr>"),
            std::string::npos);
  EXPECT_NE(direct.find("<tr><td data-h=\"option\">--pg-inverse</td><td data-h=\"value\">"
                        "analytic,lbfgs</td><td data-h=\"default\">analytic,lbfgs</td></tr>"),
            std::string::npos);
  const std::string learning = read_file(dir_ / "runs" / "learning" / "report.html");
  EXPECT_NE(learning.find("<tr><td data-h=\"option\">--lambda</td><td data-h=\"value\">0.01</td>"),
            std::string::npos);
}

}  // namespace
