// Every experiment's report, rendered at tiny sizes through the command line, and the index of
// their folders (`physgrad report`): each SVG file and each SVG inside report.html and
// index.html is well-formed, with finite coordinates inside its view box; the figures that carry
// each experiment's message exist; every table has a caption. When /usr/bin/chromium exists, the
// pages are also loaded at 420 px wide: no SVG error in the console and nothing wider than the
// page outside a table's scroll box.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli_fixture.hpp"
#include "svg_check.hpp"

namespace {

using physgrad::testing::Cli;
using physgrad::testing::read_file;
using physgrad::testing::SvgChecker;
namespace fs = std::filesystem;

struct Case {
  std::string folder, args;
  std::vector<std::string> figures;  // files that must be there (the message of the experiment)
};

const std::vector<Case>& cases() {
  static const std::vector<Case> all = {
      {"scaled-toy", "run scaled-toy --iters 200", {"loss_alpha_100.svg", "landscape_alpha_10.svg"}},
      {"sensitivity", "run sensitivity", {"step_vs_alpha.svg"}},
      {"comparison", "run comparison", {"trajectories_x.svg", "trajectories_y.svg"}},
      {"time-reversal", "run time-reversal --iters 20", {"loss_vs_passes_fpu.svg"}},
      {"hig-toy",
       "run hig-toy --seeds 2 --iters 100 --eval-every 20 --train-size 32 --test-size 16",
       {"loss_vs_time_lambda_0.01.svg", "activations_lambda_0.01.svg"}},
      {"sin-rotation",
       "run sin-rotation --xi 1,32 --time 0.1 --train-size 100 --test-size 20 --eval-every 50",
       {"x_distance_vs_time_xi_32.svg", "landscape_xi_1.svg"}},
      {"heat-inverse",
       "run heat-inverse --n 16 --train-size 32 --test-size 8 --iters 20 --eval-every 5 --batch 8",
       {"reconstruction_1.svg", "x_loss_vs_time_1d.svg"}},
      {"heat-inverse-2d",
       "run heat-inverse --dims 2 --n 8 --train-size 16 --test-size 4 --iters 10 --eval-every 5 "
       "--batch 4",
       {"sample_1.svg"}},
      {"oscillators",
       "run oscillators --train-size 32 --test-size 16 --iters 8 --eval-every 4 --batch 16",
       {"loss_vs_time_paper.svg", "trajectory.svg", "controls.svg"}},
      {"quantum-dipole",
       "run quantum-dipole --steps 24 --train-size 16 --test-size 8 --iters 6 --eval-every 3 "
       "--batch 8",
       {"loss_vs_time_dipole.svg", "dipole_density.svg", "dipole_infidelity_vs_t.svg"}},
      {"poisson",
       "run poisson --grid 4 --train-size 32 --test-size 8 --iters 10 --eval-every 5 --batch 8",
       {"loss_vs_time_poisson.svg", "fields.svg"}},
  };
  return all;
}

// The <svg>…</svg> documents embedded in an HTML page.
std::vector<std::string> inline_svgs(const std::string& html) {
  std::vector<std::string> svgs;
  for (std::size_t at = html.find("<svg"); at != std::string::npos; at = html.find("<svg", at + 1)) {
    const std::size_t end = html.find("</svg>", at);
    if (end == std::string::npos) break;
    svgs.push_back(html.substr(at, end + 6 - at));
  }
  return svgs;
}

std::size_t count(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

class ReportPages : public Cli {
 protected:
  // Runs every case into its folder and writes the index; false (with a failure) otherwise.
  bool make_reports() {
    for (const Case& c : cases()) {
      const physgrad::testing::Outcome outcome = run(c.args + " --out " + c.folder);
      if (outcome.exit_code != 0) {
        ADD_FAILURE() << c.args << ": " << outcome.err;
        return false;
      }
    }
    const physgrad::testing::Outcome index = run("report .");
    EXPECT_EQ(index.exit_code, 0) << index.err;
    EXPECT_NE(index.out.find("index of " + std::to_string(cases().size()) + " run folders"),
              std::string::npos)
        << index.out;
    return index.exit_code == 0;
  }
};

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
  EXPECT_NE(diverged.find(">diverged at 77<"), std::string::npos);
  for (const char* label : {">1e10<", ">1e100<", ">1e300<"}) {
    EXPECT_EQ(diverged.find(label), std::string::npos) << label;
  }
  const std::string index = read_file(dir_ / "index.html");
  EXPECT_NE(index.find("href=\"hig-toy/report.html\""), std::string::npos);
  const std::vector<std::string> overlays = inline_svgs(index);
  EXPECT_GE(overlays.size(), 6u);  // one per learning experiment
  for (const std::string& svg : overlays) check(svg, "index.html");
  EXPECT_GT(checked, 60u);
}

TEST_F(ReportPages, ReportOfAFolderWithoutRunFoldersIsAOneLineError) {
  fs::create_directories(dir_ / "empty" / "not-a-run");
  // Links that lead nowhere are passed over, not a filesystem error.
  fs::create_directory_symlink("loop2", dir_ / "empty" / "loop1");
  fs::create_directory_symlink("loop1", dir_ / "empty" / "loop2");
  fs::create_directory_symlink("gone", dir_ / "empty" / "dangling");
  for (const char* args : {"report empty", "report missing"}) {
    const physgrad::testing::Outcome outcome = run(args);
    EXPECT_EQ(outcome.exit_code, 2) << args;
    EXPECT_EQ(std::count(outcome.err.begin(), outcome.err.end(), '\n'), 1) << outcome.err;
    EXPECT_NE(outcome.err.find("physgrad: error: report: "), std::string::npos) << outcome.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "empty" / "index.html"));

  // A summary.json that is a FIFO is refused without blocking.
  fs::create_directories(dir_ / "fifo" / "a");
  ASSERT_EQ(::mkfifo((dir_ / "fifo" / "a" / "summary.json").c_str(), 0600), 0);
  const physgrad::testing::Outcome fifo = run("report fifo");
  EXPECT_EQ(fifo.exit_code, 2);
  EXPECT_NE(fifo.err.find("summary.json': is not a regular file (a FIFO)"), std::string::npos)
      << fifo.err;
  // Links inside a run folder that lead nowhere count as absent files.
  fs::create_directories(dir_ / "links" / "a");
  std::ofstream(dir_ / "links" / "a" / "summary.json") << R"({"experiment": "comparison", "runs": []})";
  for (const char* file : {"config.json", "metrics.csv", "report.html"}) {
    fs::create_symlink(file, dir_ / "links" / "a" / (std::string(file) + ".loop"));
    fs::create_symlink(std::string(file) + ".loop", dir_ / "links" / "a" / file);
  }
  const physgrad::testing::Outcome links = run("report links");
  EXPECT_EQ(links.exit_code, 0) << links.err;
  EXPECT_TRUE(fs::exists(dir_ / "links" / "index.html"));
}

TEST_F(ReportPages, ChromiumShowsThemWithoutErrorsAt420PixelsWide) {
  const fs::path chromium = "/usr/bin/chromium";
  if (!fs::exists(chromium)) {
    GTEST_SKIP() << "no " << chromium << " (optional: apt-get install chromium)";
  }
  ASSERT_TRUE(make_reports());
  // Each page, with a script that logs the right edge of its widest element (elements inside
  // an SVG or a table's scroll box aside), framed 420 px wide in one page.
  std::vector<std::string> pages;
  for (const Case& c : cases()) pages.push_back(c.folder + "/report.html");
  pages.push_back("index.html");
  std::string frames;
  for (std::size_t k = 0; k < pages.size(); ++k) {
    std::string html = read_file(dir_ / pages[k]);
    const std::string script =
        "<script>window.addEventListener('load', () => { let worst = 0, what = '';"
        "for (const e of document.body.querySelectorAll('*')) {"
        "if (e.closest('svg') && e.tagName.toLowerCase() !== 'svg') continue;"
        "if (e.closest('.table') && !e.classList.contains('table')) continue;"
        "const r = e.getBoundingClientRect().right; if (r > worst) { worst = r; what = e.tagName; }}"
        "console.log('physgrad-layout " + std::to_string(k) +
        " ' + window.innerWidth + ' ' + Math.ceil(worst) + ' ' + what); });</script>\n";
    html.replace(html.rfind("</body>"), 7, script + "</body>");
    const fs::path copy = dir_ / pages[k];
    std::ofstream(copy.parent_path() / ("checked_" + copy.filename().string())) << html;
    frames += "<iframe src=\"" + (fs::path(pages[k]).parent_path() /
                                  ("checked_" + fs::path(pages[k]).filename().string()))
                                     .string() +
              "\" width=\"420\" height=\"600\"></iframe>\n";
  }
  std::ofstream(dir_ / "all.html") << "<!DOCTYPE html><html><body>\n" << frames << "</body></html>\n";
  const fs::path profile = dir_ / "chromium-profile", log = dir_ / "chromium.log";
  const std::string command =
      "timeout 120 " + chromium.string() +
      " --headless --no-sandbox --disable-gpu --disable-background-networking "
      "--disable-component-update --disable-sync --no-first-run --user-data-dir='" +
      profile.string() +
      "' --enable-logging=stderr --v=0 --window-size=1000,1000 --virtual-time-budget=10000 "
      "--dump-dom 'file://" +
      (dir_ / "all.html").string() + "' > /dev/null 2> '" + log.string() + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << read_file(log);
  const std::string console = read_file(log);
  EXPECT_EQ(console.find("Error: <"), std::string::npos) << console;
  for (std::size_t k = 0; k < pages.size(); ++k) {
    const std::string tag = "\"physgrad-layout " + std::to_string(k) + " ";
    const std::size_t at = console.find(tag);
    ASSERT_NE(at, std::string::npos) << pages[k] << " was not laid out:\n" << console;
    int width = 0, right = 0;
    ASSERT_EQ(std::sscanf(console.c_str() + at + tag.size(), "%d %d", &width, &right), 2);
    EXPECT_EQ(width, 420) << pages[k];
    EXPECT_LE(right, width) << pages[k] << ": " << console.substr(at, 80);
  }
}

}  // namespace
