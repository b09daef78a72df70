// What a reader takes from a report: the command it shows runs again as printed (a fresh folder,
// option values the parser takes back), every report and summary.json name the machine and
// build, the link to the index only where there is one, every plotted point has a hover value
// (with its band's ends), log axes say so, and the index has a table of contents of anchors.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "cli_fixture.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "registry.hpp"
#include "report_pages_fixture.hpp"

namespace {

using physgrad::LinePlotOptions;
using physgrad::Series;
using physgrad::line_plot_svg;
using physgrad::testing::link_attributes;
using physgrad::testing::read_file;
namespace fs = std::filesystem;
namespace ex = physgrad::run;

class ReaderPages : public physgrad::testing::Cli {};

// The text of HTML with xml_escape's five entities turned back.
std::string unescaped(std::string text) {
  for (const auto& [entity, c] : {std::pair("&lt;", "<"), std::pair("&gt;", ">"),
                                  std::pair("&quot;", "\""), std::pair("&#39;", "'"),
                                  std::pair("&amp;", "&")}) {
    for (std::size_t at = text.find(entity); at != std::string::npos;
         at = text.find(entity, at + 1)) {
      text.replace(at, std::string(entity).size(), c);
    }
  }
  return text;
}

TEST_F(ReaderPages, TheCommandOnAReportRunsAgainAndEveryOptionValueReadsBack) {
  ASSERT_EQ(run("run sin-rotation --xi 1 --time 0.05 --train-size 10000 --test-size 20 "
                "--eval-every 50 --phi 12.5 --out a")
                .exit_code,
            0);
  const std::string html = read_file(dir_ / "a" / "report.html");
  const std::string lead = "To run it again (into a new folder under runs/): ";
  const std::size_t at = html.find(lead);
  ASSERT_NE(at, std::string::npos) << "no command to run it again";
  const std::string command =
      unescaped(html.substr(at + lead.size(), html.find("</p>", at) - at - lead.size()));
  EXPECT_EQ(command.rfind("physgrad run sin-rotation ", 0), 0u) << command;
  EXPECT_NE(command.find(" --train-size 10000 "), std::string::npos) << command;
  EXPECT_EQ(command.find("--out"), std::string::npos) << command;
  // Copied as printed, it runs (twice: each time into a folder of its own).
  for (int k = 0; k < 2; ++k) {
    const physgrad::testing::Outcome again = run(command.substr(std::string("physgrad ").size()));
    ASSERT_EQ(again.exit_code, 0) << command << "\n" << again.err;
  }
  std::size_t folders = 0;
  for (const auto& entry : fs::directory_iterator(dir_ / "runs")) {
    folders += fs::is_regular_file(entry.path() / "report.html");
  }
  EXPECT_EQ(folders, 2u);
  // Every value of the table of options is text the option parser takes, with the value the
  // run had (config.json).
  const ex::Experiment& experiment = physgrad::experiments::builtin_registry().find("sin-rotation");
  const std::vector<ex::OptionSpec> specs = ex::all_options(experiment);
  const nlohmann::json settings =
      nlohmann::json::parse(read_file(dir_ / "a" / "config.json")).at("settings");
  const std::regex row(
      "<td data-h=\"option\">--([a-z0-9-]+)</td><td data-h=\"value\">([^<]*)</td>");
  std::size_t checked = 0;
  for (std::sregex_iterator it(html.begin(), html.end(), row), end; it != end; ++it) {
    const std::string name = (*it)[1], text = unescaped((*it)[2]);
    if (text == "unset") continue;
    const ex::OptionSpec& spec = ex::find_option(experiment, specs, name);
    nlohmann::json parsed;
    EXPECT_NO_THROW(parsed = ex::parse_option(spec, text)) << "--" << name << " " << text;
    EXPECT_EQ(parsed, settings.at(name)) << "--" << name << " " << text;
    ++checked;
  }
  EXPECT_GT(checked, 10u);
}

TEST_F(ReaderPages, EveryReportAndSummaryNameCommitCpuBlasThreadsAndDate) {
  ASSERT_EQ(run("run comparison --iters 3 --out d").exit_code, 0);
  const nlohmann::json summary = nlohmann::json::parse(read_file(dir_ / "d" / "summary.json"));
  ASSERT_TRUE(summary.contains("runs"));  // the existing keys stay
  ASSERT_TRUE(summary.contains("machine")) << summary.dump();
  const nlohmann::json& machine = summary.at("machine");
  for (const char* key : {"commit", "cpu", "blas", "blas_kernel", "date"}) {
    ASSERT_TRUE(machine.contains(key) && machine.at(key).is_string()) << key;
    EXPECT_FALSE(machine.at(key).get<std::string>().empty()) << key;
  }
  for (const char* key : {"blas_threads", "jacobian_threads", "hardware_threads"}) {
    ASSERT_TRUE(machine.contains(key) && machine.at(key).is_number_integer()) << key;
  }
  EXPECT_TRUE(std::regex_match(machine.at("date").get<std::string>(),
                               std::regex(R"(\d{4}-\d\d-\d\d \d\d:\d\d UTC)")));
  const std::string html = read_file(dir_ / "d" / "report.html");
  EXPECT_NE(html.find("commit " + machine.at("commit").get<std::string>() + " · CPU "),
            std::string::npos);
  EXPECT_NE(html.find(" (kernel " + machine.at("blas_kernel").get<std::string>() + ")"),
            std::string::npos);
  EXPECT_NE(html.find("threads: BLAS " + machine.at("blas_threads").dump()), std::string::npos);
}

TEST_F(ReaderPages, AReportLinksTheIndexOnlyWhenThereIsOne) {
  ASSERT_EQ(run("run comparison --iters 3 --out runs/first").exit_code, 0);
  const auto links_index = [&](const std::string& folder) {
    const std::vector<std::string> links =
        link_attributes(read_file(dir_ / "runs" / folder / "report.html"));
    return std::find(links.begin(), links.end(), "../index.html") != links.end();
  };
  EXPECT_FALSE(links_index("first")) << "a link to an index that is not there";
  ASSERT_EQ(run("report runs").exit_code, 0);
  ASSERT_EQ(run("run comparison --iters 3 --out runs/second").exit_code, 0);
  EXPECT_TRUE(links_index("second"));
  EXPECT_TRUE(fs::is_regular_file(dir_ / "runs" / "index.html"));
  // The index: a table of contents whose every link is an anchor on the page.
  const std::string index = read_file(dir_ / "runs" / "index.html");
  ASSERT_NE(index.find("<nav class=\"contents\">"), std::string::npos);
  const std::regex anchor("href=\"#([^\"]+)\"");
  std::size_t anchors = 0;
  for (std::sregex_iterator it(index.begin(), index.end(), anchor), end; it != end; ++it) {
    EXPECT_NE(index.find("id=\"" + (*it)[1].str() + "\""), std::string::npos) << (*it)[1];
    ++anchors;
  }
  EXPECT_GE(anchors, 3u);  // the experiment, every run, the commands
}

TEST(ReaderPlots, EveryPlottedPointHasAHoverValueWithItsBand) {
  Series s{"median", {}, {}};
  for (int k = 0; k < 150; ++k) {
    s.x.push_back(k);
    s.y.push_back(1.0 + k);
    s.band_low.push_back(0.5 + k);
    s.band_high.push_back(2.0 + k);
  }
  s.markers = true;
  const std::string svg = line_plot_svg({s}, {"t", "step", "loss"});
  for (int k = 0; k < 150; ++k) {
    const std::string title = "<title>median: step = " + std::to_string(k) +
                              ", loss = " + std::to_string(k + 1) + " (from ";
    EXPECT_NE(svg.find(title), std::string::npos) << title;
  }
}

TEST(ReaderPlots, LogAxesSayTheyAreLog) {
  const Series s{"a", {1, 10, 100}, {1, 0.1, 0.01}};
  LinePlotOptions options{"t", "step", "loss"};
  EXPECT_EQ(line_plot_svg({s}, options).find("(log scale)"), std::string::npos);
  options.log_y = true;
  const std::string log_y = line_plot_svg({s}, options);
  EXPECT_NE(log_y.find(">loss (log scale)<"), std::string::npos);
  EXPECT_EQ(log_y.find(">step (log scale)<"), std::string::npos);
  options.log_x = true;
  EXPECT_NE(line_plot_svg({s}, options).find(">step (log scale)<"), std::string::npos);
}

}  // namespace
