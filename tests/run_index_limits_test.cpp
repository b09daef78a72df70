// What the index of run folders (`physgrad report DIR`) does with folders it cannot show in full:
// a field of the wrong type leaves the folder out with a one-line warning; files far larger than
// any run writes are read in part, in bounded time and memory; and memory does not grow with the
// number of folders beyond the few bytes each adds to the page's spool index.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "report_pages_fixture.hpp"

namespace {

using physgrad::testing::read_file;
using physgrad::testing::ReportPages;
// Run folders the index cannot show in full, and many of them.
class RunIndexLimits : public ReportPages {};
namespace fs = std::filesystem;

TEST_F(RunIndexLimits, AFolderWithAFieldOfTheWrongTypeIsLeftOutWithAOneLineWarning) {
  ASSERT_EQ(run("run comparison --iters 2 --out runs/good").exit_code, 0);
  const auto broken = [&](const std::string& name, const std::string& file,
                          const std::function<void(nlohmann::json&)>& edit) {
    fs::copy(dir_ / "runs" / "good", dir_ / "runs" / name);
    nlohmann::json document = nlohmann::json::parse(read_file(dir_ / "runs" / name / file));
    edit(document);
    std::ofstream(dir_ / "runs" / name / file) << document.dump();
  };
  broken("command", "config.json", [](nlohmann::json& j) { j["command"] = 5; });
  broken("label", "summary.json", [](nlohmann::json& j) { j["runs"][1]["label"] = {1, 2}; });
  broken("loss", "summary.json", [](nlohmann::json& j) { j["runs"][0]["final"]["loss"] = "low"; });
  broken("experiment", "summary.json", [](nlohmann::json& j) { j["experiment"] = true; });
  broken("params", "summary.json", [](nlohmann::json& j) { j["runs"][2]["params"] = 3; });
  broken("config", "config.json", [](nlohmann::json& j) { j = nlohmann::json::array(); });
  const physgrad::testing::Outcome outcome = run("report runs");
  ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
  const std::vector<std::string> warnings = {
      "'runs/command/config.json': command is a number, not text",
      "'runs/config/config.json': holds an array, not an object",
      "'runs/experiment/summary.json': experiment is a boolean, not text",
      "'runs/label/summary.json': runs[1].label is an array, not text",
      "'runs/loss/summary.json': runs[0].final.loss is a string, not a number",
      "'runs/params/summary.json': runs[2].params is a number, not an object"};
  std::string expected;
  for (const std::string& w : warnings) {
    expected += "physgrad: warning: report: " + w + "; the folder is left out\n";
  }
  EXPECT_EQ(outcome.err, expected);
  const std::string index = read_file(dir_ / "runs" / "index.html");
  EXPECT_NE(index.find("<h2>Left out</h2>"), std::string::npos);
  for (const std::string& w : warnings) {
    std::string escaped = w;
    for (std::size_t at = escaped.find('\''); at != std::string::npos;
         at = escaped.find('\'', at)) {
      escaped.replace(at, 1, "&#39;");
    }
    EXPECT_NE(index.find("<p>" + escaped + "; the folder is left out</p>"), std::string::npos) << w;
  }
  EXPECT_NE(index.find("href=\"./good/report.html\""), std::string::npos);
  EXPECT_EQ(index.find("href=\"./label/report.html\""), std::string::npos);
  EXPECT_EQ(outcome.out, "index of 1 run folders: runs/index.html\n");
}

// Files far larger than any run writes are read only in part, in time linear in what is read and
// memory bounded whatever the content; the page and stderr say what is left out. Comparing every
// run of a label with every other would take minutes here, and keeping every cell of the line of
// commas 32 bytes per comma, beyond the address space given.
TEST_F(RunIndexLimits, LargeFilesAreReadInBoundedTimeAndMemoryAndWhatIsLeftOutIsSaid) {
  const auto folder = [&](const std::string& name, const std::string& summary) {
    fs::create_directories(dir_ / "runs" / name);
    std::ofstream(dir_ / "runs" / name / "summary.json") << summary;
    return dir_ / "runs" / name;
  };
  const std::string one_run =
      R"({"experiment": "hig-toy", "runs": [{"label": "L", "final": {"test_loss": 1}}]})";
  // 12,000 runs of one label, 40 values of alpha with 300 seeds each.
  nlohmann::json runs = nlohmann::json::array();
  for (int k = 0; k < 12000; ++k) {
    runs.push_back({{"label", "L"},
                    {"params", {{"alpha", k % 40}, {"seed", k / 40}}},
                    {"final", {{"loss", 1.0 / (1 + k)}}},
                    {"iterations", 10},
                    {"wall_seconds", 0.5},
                    {"termination", "max_iterations"}});
  }
  folder("many", nlohmann::json{{"experiment", "scaled-toy"}, {"runs", runs}}.dump());
  // A metrics.csv of 20 MiB of commas, one of more than 32 MiB (sparse), one of 200,100 rows and
  // one of 300 seeds.
  std::ofstream(folder("wide", one_run) / "metrics.csv") << std::string(20 << 20, ',');
  {
    std::ofstream(folder("huge", one_run) / "metrics.csv") << "label,seed,wall_seconds,test_loss\n";
  }
  fs::resize_file(dir_ / "runs" / "huge" / "metrics.csv", (std::size_t{32} << 20) + 1);
  std::string rows = "label,seed,wall_seconds,test_loss\n";
  for (int k = 0; k < 200100; ++k) rows += "L,0," + std::to_string(k) + ",1\n";
  std::ofstream(folder("long", one_run) / "metrics.csv") << rows;
  rows = "label,seed,wall_seconds,test_loss\n";
  for (int k = 0; k < 300; ++k) rows += "L," + std::to_string(k) + ",1,1\n";
  std::ofstream(folder("seeds", one_run) / "metrics.csv") << rows;

  const auto start = std::chrono::steady_clock::now();
  // Within an address space of 1 GiB (prlimit, run by `env`), which the line of commas alone once
  // exceeded; AddressSanitizer reserves terabytes of address space at start, so not in its build.
#if defined(__SANITIZE_ADDRESS__)
  const physgrad::testing::Outcome outcome = run("report runs");
#else
  const physgrad::testing::Outcome outcome = run("report runs", "prlimit --as=1073741824");
#endif
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
  EXPECT_LT(seconds, 30) << "quadratic somewhere?";
  // Each metrics.csv's limits twice: for the interactive comparison and for the figures.
  const std::vector<std::string> warnings = {
      "'runs/huge/metrics.csv': is 33554433 bytes, more than the 33554432 allowed; not in the "
      "interactive comparison",
      "'runs/huge/metrics.csv': is 33554433 bytes, more than the 33554432 allowed; its loss "
      "curves are not drawn",
      "'runs/long/metrics.csv': 200100 rows, only the first 200000 are in the interactive "
      "comparison",
      "'runs/long/metrics.csv': 200100 rows, only the first 200000 are drawn",
      "'runs/many/summary.json': 12000 runs, only the first 10000 are listed",
      "'runs/seeds/metrics.csv': more than 256 runs, the 44 rows of the others are not in the "
      "interactive comparison",
      "'runs/seeds/metrics.csv': more than 256 curves (label and seed), the 44 rows of the "
      "others are not drawn",
      "'runs/wide/metrics.csv': csv: the header has 20971521 cells, more than the 4096 read; "
      "not in the interactive comparison",
      "'runs/wide/metrics.csv': csv: the header has 20971521 cells, more than the 4096 read; "
      "its loss curves are not drawn"};
  std::string expected;
  for (const std::string& w : warnings) expected += "physgrad: warning: report: " + w + "\n";
  EXPECT_EQ(outcome.err, expected);
  const std::string index = read_file(dir_ / "runs" / "index.html");
  EXPECT_NE(index.find("<p>&#39;runs/many/summary.json&#39;: 12000 runs, only the first 10000 are "
                       "listed</p>"),
            std::string::npos);
  // 10,000 runs of "many" in 40 rows of 250 seeds, the setting named by alpha alone.
  EXPECT_NE(index.find("<td data-h=\"run\">L</td><td data-h=\"setting\">alpha = 0</td>"
                       "<td data-h=\"runs\">250</td>"),
            std::string::npos);
  EXPECT_NE(index.find("<td data-h=\"run\">L</td><td data-h=\"setting\">alpha = 39</td>"
                       "<td data-h=\"runs\">250</td>"),
            std::string::npos);
}

// The peak memory (the kernel's maximum resident set, KiB) of the process `pid` once it ends,
// and its exit code.
std::pair<long, int> peak_kib(pid_t pid) {
  int status = 0;
  rusage usage{};
  if (::wait4(pid, &status, 0, &usage) != pid) return {-1, -1};
  return {usage.ru_maxrss, WIFEXITED(status) ? WEXITSTATUS(status) : -1};
}

// `physgrad report` holds of each folder only a few bytes once it is read (where its part of the
// page lies in the spool file, its path): 240 folders take no more memory than 24 but for 4 KiB
// a folder (docs/cli.md). The folders are copies (hard links) of one learning run folder of 8
// rules × 50 seeds with 6,400 rows of metrics, so that each adds to every table of the page.
TEST_F(RunIndexLimits, MemoryDoesNotGrowWithTheNumberOfFolders) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer keeps freed memory in quarantine: peaks measure it";
#endif
  nlohmann::json runs = nlohmann::json::array();
  for (int k = 0; k < 400; ++k) {
    runs.push_back({{"label", "Rule " + std::to_string(k % 8)},
                    {"optimizer", "adam"},
                    {"params", {{"seed", k / 8}, {"lr", 0.01}}},
                    {"final", {{"loss", 0.5 + 1e-3 * k}, {"test_loss", 0.4 + 1e-3 * k}}},
                    {"iterations", 200},
                    {"epochs", 10.0},
                    {"wall_seconds", 0.5},
                    {"termination", "max_iterations"}});
  }
  const fs::path one = dir_ / "one";
  fs::create_directories(one);
  std::ofstream(one / "summary.json")
      << nlohmann::json{{"experiment", "hig-toy"},
                        {"runs", runs},
                        {"message",
                         {{"figure", "x.svg"}, {"sentence", "Rule 0 is lowest."},
                          {"metric", "test_loss"}, {"metric_text", "final test loss"}}}}
             .dump();
  std::ofstream(one / "config.json")
      << R"({"experiment": "hig-toy", "command": "physgrad run hig-toy", "settings": {}})";
  {
    std::ofstream metrics(one / "metrics.csv");
    metrics << "label,seed,iteration,wall_seconds,test_loss\n";
    for (int rule = 0; rule < 8; ++rule) {
      for (int seed = 0; seed < 4; ++seed) {
        for (int i = 0; i < 200; ++i) {
          metrics << "Rule " << rule << "," << seed << "," << i << "," << 0.01 * i << ","
                  << 1.0 / (1 + i + rule) << "\n";
        }
      }
    }
  }
  const auto copies = [&](const std::string& name, int count) {
    for (int k = 0; k < count; ++k) {
      const fs::path folder = dir_ / name / ("run" + std::to_string(1000 + k));
      fs::create_directories(folder);
      for (const char* file : {"summary.json", "config.json", "metrics.csv"}) {
        fs::create_hard_link(one / file, folder / file);
      }
    }
  };
  copies("few", 24);
  copies("many", 240);
  const auto [few, few_exit] = peak_kib(spawn("report few"));
  const auto [many, many_exit] = peak_kib(spawn("report many"));
  ASSERT_EQ(few_exit, 0);
  ASSERT_EQ(many_exit, 0);
  EXPECT_LT(many - few, 216 * 4) << "KiB: 24 folders took " << few << ", 240 took " << many;
  const std::string index = read_file(dir_ / "many" / "index.html");
  // Every folder is in the page: its rows of the comparison and of the table of every run.
  EXPECT_NE(index.find("<td data-h=\"run folder\">run1239</td><td data-h=\"options\">"),
            std::string::npos);
  EXPECT_NE(index.find("<td data-h=\"run folder\">run1239</td><td data-h=\"experiment\">"),
            std::string::npos);
  RecordProperty("peak_kib_24_folders", std::to_string(few));
  RecordProperty("peak_kib_240_folders", std::to_string(many));
}

}  // namespace
