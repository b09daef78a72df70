// Every experiment's report, rendered at tiny sizes through the command line, and the index of
// their folders (`physgrad report`): each SVG file and each SVG inside report.html and
// index.html is well-formed, with finite coordinates inside its view box; the figures that carry
// each experiment's message exist, and each report opens with the message figure that
// docs/results.md names; every table has a caption. When Chromium is installed, the pages are
// also loaded at 420 px wide: no SVG error in the console, nothing wider than the page outside
// a table's or a figure's scroll box, and no text inside a figure below 11 px. Run folders with
// hostile names and contents (a script or another site as a link, bytes that are not UTF-8,
// bidirectional controls, fields of the wrong type, huge files) give pages whose every link is
// a local file, that run no script and ask no server, are valid UTF-8 and XML, and an index
// that says what it left out.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <iconv.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "cli_fixture.hpp"
#include "physgrad/report/html_report.hpp"
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

// The <svg>…</svg> documents embedded in an HTML page (the outermost ones: a figure's layouts
// are nested <svg>s inside it).
std::vector<std::string> inline_svgs(const std::string& html) {
  std::vector<std::string> svgs;
  std::size_t at = html.find("<svg");
  while (at != std::string::npos) {
    std::size_t depth = 1, next = at + 4, end = std::string::npos;
    while (depth > 0) {
      const std::size_t open = html.find("<svg", next), close = html.find("</svg>", next);
      if (close == std::string::npos) break;
      if (open != std::string::npos && open < close) {
        ++depth;
        next = open + 4;
      } else {
        --depth;
        next = close + 6;
        end = close;
      }
    }
    if (depth > 0) break;
    svgs.push_back(html.substr(at, end + 6 - at));
    at = html.find("<svg", end + 6);
  }
  return svgs;
}

std::size_t count(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

// Where `text` is not what a page may hold: a byte that is not UTF-8, a character XML forbids
// (C0 controls but tab, newline and CR; U+FFFE, U+FFFF) or a bidirectional control (U+202A–E,
// U+2066–9); empty when it is fine. Decoded by iconv, independently of the library.
std::string page_text_problem(const std::string& text) {
  const iconv_t to_utf32 = ::iconv_open("UTF-32LE", "UTF-8");
  if (to_utf32 == reinterpret_cast<iconv_t>(-1)) return "iconv cannot decode UTF-8";
  std::vector<char> out(4 * text.size() + 4);
  std::string copy = text;
  char* in_at = copy.data();
  char* out_at = out.data();
  std::size_t in_left = copy.size(), out_left = out.size();
  const std::size_t done = ::iconv(to_utf32, &in_at, &in_left, &out_at, &out_left);
  ::iconv_close(to_utf32);
  if (done == static_cast<std::size_t>(-1) || in_left != 0) {
    const std::size_t at = static_cast<std::size_t>(in_at - copy.data());
    return "not UTF-8 at byte " + std::to_string(at) + ": '" +
           text.substr(at > 20 ? at - 20 : 0, 40) + "'";
  }
  for (const char* c = out.data(); c < out_at; c += 4) {
    const std::uint32_t u = static_cast<std::uint32_t>(static_cast<unsigned char>(c[0])) |
                            static_cast<std::uint32_t>(static_cast<unsigned char>(c[1])) << 8 |
                            static_cast<std::uint32_t>(static_cast<unsigned char>(c[2])) << 16;
    if ((u < 0x20 && u != '\t' && u != '\n' && u != '\r') || u == 0xFFFE || u == 0xFFFF ||
        (u >= 0x202A && u <= 0x202E) || (u >= 0x2066 && u <= 0x2069)) {
      return "code point " + std::to_string(u) + " at character " +
             std::to_string((c - out.data()) / 4);
    }
  }
  return {};
}

// The values of every href and src attribute in `html`, as written.
std::vector<std::string> link_attributes(const std::string& html) {
  static const std::regex attribute(R"re(\s(?:href|src)\s*=\s*("[^"]*"|'[^']*'|[^\s>]+))re",
                                    std::regex::icase);
  std::vector<std::string> values;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), attribute);
       it != std::sregex_iterator(); ++it) {
    std::string value = (*it)[1];
    if (value[0] == '"' || value[0] == '\'') value = value.substr(1, value.size() - 2);
    values.push_back(value);
  }
  return values;
}

// `text` with its %XX escapes decoded (the bytes of a file name in a file:// address).
std::string percent_decoded(const std::string& text) {
  std::string out;
  for (std::size_t k = 0; k < text.size(); ++k) {
    if (text[k] == '%' && k + 2 < text.size() &&
        std::isxdigit(static_cast<unsigned char>(text[k + 1])) &&
        std::isxdigit(static_cast<unsigned char>(text[k + 2]))) {
      out += static_cast<char>(std::stoi(text.substr(k + 1, 2), nullptr, 16));
      k += 2;
    } else {
      out += text[k];
    }
  }
  return out;
}

// True when `file` exists, is a regular file and lies inside `folder` (links followed).
bool is_file_inside(const fs::path& file, const fs::path& folder) {
  std::error_code error;
  const fs::path real = fs::canonical(file, error), root = fs::canonical(folder, error);
  if (error || !fs::is_regular_file(real, error)) return false;
  const std::string r = real.string(), f = root.string() + "/";
  return r.compare(0, f.size(), f) == 0;
}

// Debian's Chromium itself, without its launcher /usr/bin/chromium: the launcher adds Google's API
// keys and extensions, and with them sign-in and update requests of the browser's own.
constexpr const char* kChromium = "/usr/lib/chromium/chromium";

// Headless Chromium on `page` (a file), its console and errors in `log`; the exit status.
int run_chromium(const fs::path& page, const fs::path& profile, const fs::path& log,
                 const std::string& flags = "") {
  const std::string command =
      "timeout 120 " + std::string(kChromium) +
      " --headless --no-sandbox --disable-gpu "
      "--disable-background-networking --disable-component-update --disable-sync "
      "--no-first-run --user-data-dir='" +
      profile.string() + "' --enable-logging=stderr --v=0 --window-size=1000,1000 " +
      "--virtual-time-budget=10000 " + flags + " --dump-dom 'file://" + page.string() +
      "' > /dev/null 2> '" + log.string() + "'";
  return std::system(command.c_str());
}

// The messages `console.log("physgrad-TAG …")` left in a Chromium log: the text after the tag.
std::vector<std::string> console_messages(const std::string& log, const std::string& tag) {
  std::vector<std::string> found;
  const std::string start = "\"physgrad-" + tag + " ";
  for (std::size_t at = log.find(start); at != std::string::npos; at = log.find(start, at + 1)) {
    const std::size_t from = at + start.size(), end = log.find('"', from);
    found.push_back(log.substr(from, end - from));
  }
  return found;
}

// A TCP server on 127.0.0.1 that records the first line of every request made to it, to serve as
// the proxy of every address a browser asks for: nothing can reach the network without showing.
// The host a request to a proxy names: "GET http://HOST/…" or "CONNECT HOST:443 …".
std::string requested_host(const std::string& request) {
  std::string target = request.substr(request.find(' ') + 1);
  target = target.substr(0, target.find(' '));
  if (const std::size_t scheme = target.find("://"); scheme != std::string::npos) {
    target = target.substr(scheme + 3);
  }
  return target.substr(0, target.find_first_of(":/"));
}

// Chromium asks Google's services (sign-in, component updates, network time) of its own accord,
// whatever it shows and whichever switches it is given.
bool is_browser_service(std::string_view host) {
  return host.ends_with(".google.com") || host.ends_with(".googleapis.com") ||
         host.ends_with(".gvt1.com");
}

class Listener {
 public:
  Listener() {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof address;
    if (fd_ < 0 || ::bind(fd_, reinterpret_cast<sockaddr*>(&address), length) != 0 ||
        ::listen(fd_, 64) != 0 ||
        ::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
      ADD_FAILURE() << "cannot listen on 127.0.0.1: " << std::strerror(errno);
      return;
    }
    port_ = ntohs(address.sin_port);
    thread_ = std::thread([this] { serve(); });
  }
  ~Listener() { stop(); }
  int port() const { return port_; }
  // Stops listening; the first line of every request received.
  std::vector<std::string> stop() {
    stopping_ = true;
    if (thread_.joinable()) thread_.join();
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    return requests_;
  }

 private:
  void serve() {
    while (!stopping_) {
      pollfd waiting{fd_, POLLIN, 0};
      if (::poll(&waiting, 1, 50) <= 0) continue;
      const int connection = ::accept(fd_, nullptr, nullptr);
      if (connection < 0) continue;
      std::string request;
      pollfd reading{connection, POLLIN, 0};
      std::array<char, 512> buffer{};
      if (::poll(&reading, 1, 2000) > 0) {
        const ssize_t n = ::read(connection, buffer.data(), buffer.size());
        if (n > 0) request.assign(buffer.data(), static_cast<std::size_t>(n));
      }
      requests_.push_back(request.substr(0, request.find('\r')));
      ::close(connection);  // no answer: the browser sees a failed request
    }
  }

  int fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
  std::vector<std::string> requests_;
};

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

  // Run folders in runs/ that attack its index: names that read as a script or another site when
  // linked as they are, or that hold the characters ending a URL's path (# ?), an escape (%) and
  // a byte that is not UTF-8; a learning folder written by hand whose experiment and labels (in
  // summary.json and metrics.csv) hold bidirectional controls, U+FFFF, a control character and
  // a byte that is not UTF-8. Then `physgrad report runs`; false (with a failure) when a step
  // fails.
  bool make_hostile_index() {
    for (const std::string& name :
         {kScriptName, std::string("http:127.0.0.1:9"), std::string("http:attacker.invalid"),
          std::string("a#b?c%41 d"), std::string("plain")}) {
      const physgrad::testing::Outcome outcome =
          run("run comparison --iters 2 --out 'runs/" + name + "'");
      if (outcome.exit_code != 0) {
        ADD_FAILURE() << name << ": " << outcome.err;
        return false;
      }
    }
    fs::rename(dir_ / "runs" / "plain", dir_ / "runs" / kNotUtf8Name);
    const fs::path learning = dir_ / "runs" / "learning";
    fs::create_directories(learning);
    std::ofstream(learning / "summary.json")
        << R"({"experiment": "hig-toy\u202e", "runs": [{"label": "Adam\u202eevil\uffff\u0001",)"
        << R"( "params": {"seed": 0}, "final": {"test_loss": 0.5}}]})";
    const std::string label =
        "Adam\xe2\x80\xae"
        "evil\xef\xbf\xbf\x01\xff\xe2\x81\xa6";
    std::ofstream(learning / "metrics.csv") << "label,seed,wall_seconds,test_loss\n"
                                            << label << ",0,0.5,1\n"
                                            << label << ",0,1,0.5\n";
    const physgrad::testing::Outcome index = run("report runs");
    EXPECT_EQ(index.exit_code, 0) << index.err;
    EXPECT_EQ(index.err, "");
    return index.exit_code == 0;
  }

  // index.html and every report.html of the hostile runs, relative to runs/.
  std::vector<std::string> hostile_pages() const {
    std::vector<std::string> pages = {"index.html"};
    for (const auto& entry : fs::directory_iterator(dir_ / "runs")) {
      if (fs::exists(entry.path() / "report.html")) {
        pages.push_back(entry.path().filename().string() + "/report.html");
      }
    }
    return pages;
  }

  // The link in a console message of Chromium (a resolved address) is a file inside runs/.
  void expect_local_file(const std::string& address, const std::string& page) const {
    const std::string prefix = "file://" + (dir_ / "runs").string() + "/";
    EXPECT_EQ(address.rfind(prefix, 0), 0u) << page << " links to " << address;
    EXPECT_EQ(address.find_first_of("?#"), std::string::npos) << page << " links to " << address;
    EXPECT_TRUE(is_file_inside(percent_decoded(address.substr(7)), dir_ / "runs"))
        << page << " links to " << address << ", not to a file inside runs/";
  }

  inline static const std::string kScriptName = "javascript:void(window.pwned=1)";
  inline static const std::string kNotUtf8Name = "not-utf8-\xff";
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
    if (c.folder != name) continue;  // a variant (e.g. 2-D) names its files differently
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
  EXPECT_EQ(checked + 1, cases().size());  // all but the 2-D variant
  EXPECT_EQ(messages.size(), checked);    // and no documented experiment without a case
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

  // A summary.json that is a FIFO is refused without blocking: no folder is left to show.
  fs::create_directories(dir_ / "fifo" / "a");
  ASSERT_EQ(::mkfifo((dir_ / "fifo" / "a" / "summary.json").c_str(), 0600), 0);
  const physgrad::testing::Outcome fifo = run("report fifo");
  EXPECT_EQ(fifo.exit_code, 2);
  EXPECT_EQ(
      fifo.err,
      "physgrad: error: report: 'fifo' holds no run folder (a folder with summary.json) that "
      "can be read: 'fifo/a/summary.json': is not a regular file (a FIFO); the folder is left "
      "out\n");
  // A metrics.csv that is a FIFO leaves out the folder's curves, named once.
  fs::create_directories(dir_ / "fifo-metrics" / "a");
  std::ofstream(dir_ / "fifo-metrics" / "a" / "summary.json")
      << R"({"experiment": "hig-toy", "runs": []})";
  ASSERT_EQ(::mkfifo((dir_ / "fifo-metrics" / "a" / "metrics.csv").c_str(), 0600), 0);
  const physgrad::testing::Outcome metrics = run("report fifo-metrics");
  EXPECT_EQ(metrics.exit_code, 0);
  EXPECT_EQ(metrics.err,
            "physgrad: warning: report: 'fifo-metrics/a/metrics.csv': is not a regular file (a "
            "FIFO); its loss curves are not drawn\n");
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
  if (!fs::exists(kChromium)) GTEST_SKIP() << "no " << kChromium << " (make test installs it)";
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
        "const boxes = '.table, .figure-scroll';"
        "for (const e of document.body.querySelectorAll('*')) {"
        "if (e.closest('svg') && e.tagName.toLowerCase() !== 'svg') continue;"
        "if (e.parentElement && e.parentElement.closest(boxes)) continue;"
        "const r = e.getBoundingClientRect().right; if (r > worst) { worst = r; what = e.tagName; }}"
        "let smallest = 1e9, text = '';"
        "for (const t of document.querySelectorAll('svg text')) {"
        "const svg = t.ownerSVGElement; const box = svg.viewBox.baseVal;"
        "if (!box || box.width === 0) continue;"
        "if (svg.getBoundingClientRect().width === 0) continue;"
        "const px = parseFloat(getComputedStyle(t).fontSize) *"
        " svg.getBoundingClientRect().width / box.width;"
        "if (px < smallest) { smallest = px; text = t.textContent.slice(0, 20); }}"
        "console.log('physgrad-layout " + std::to_string(k) +
        " ' + window.innerWidth + ' ' + Math.ceil(worst) + ' ' + smallest.toFixed(2) + ' ' +"
        " what + ' ' + text); });</script>\n";
    html.replace(html.rfind("</body>"), 7, script + "</body>");
    const fs::path copy = dir_ / pages[k];
    std::ofstream(copy.parent_path() / ("checked_" + copy.filename().string())) << html;
    frames += "<iframe src=\"" + (fs::path(pages[k]).parent_path() /
                                  ("checked_" + fs::path(pages[k]).filename().string()))
                                     .string() +
              "\" width=\"420\" height=\"600\"></iframe>\n";
  }
  std::ofstream(dir_ / "all.html") << "<!DOCTYPE html><html><body>\n" << frames << "</body></html>\n";
  const fs::path log = dir_ / "chromium.log";
  ASSERT_EQ(run_chromium(dir_ / "all.html", dir_ / "chromium-profile", log), 0) << read_file(log);
  const std::string console = read_file(log);
  EXPECT_EQ(console.find("Error: <"), std::string::npos) << console;
  for (std::size_t k = 0; k < pages.size(); ++k) {
    const std::string tag = "\"physgrad-layout " + std::to_string(k) + " ";
    const std::size_t at = console.find(tag);
    ASSERT_NE(at, std::string::npos) << pages[k] << " was not laid out:\n" << console;
    int width = 0, right = 0;
    double smallest_text = 0;
    ASSERT_EQ(std::sscanf(console.c_str() + at + tag.size(), "%d %d %lf", &width, &right,
                          &smallest_text),
              3);
    EXPECT_EQ(width, 420) << pages[k];
    EXPECT_LE(right, width) << pages[k] << ": " << console.substr(at, 80);
    // Text inside figures stays readable: at least 11 px (figures scroll rather than shrink).
    EXPECT_GE(smallest_text, 10.99) << pages[k] << ": " << console.substr(at, 120);
  }
}

TEST_F(ReportPages, HostileFolderNamesAndLabelsGiveLocalLinksAndValidPages) {
  ASSERT_TRUE(make_hostile_index());
  std::size_t links = 0;
  for (const std::string& page : hostile_pages()) {
    const fs::path file = dir_ / "runs" / page;
    const std::string html = read_file(file);
    EXPECT_EQ(page_text_problem(html), "") << page;
    EXPECT_EQ(html.find("<script"), std::string::npos) << page;
    for (const std::string& link : link_attributes(html)) {
      ++links;
      EXPECT_EQ(link.rfind("./", 0), 0u) << page << ": " << link;
      EXPECT_EQ(link.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
                                       "0123456789-._~%/"),
                std::string::npos)
          << page << ": " << link;
      EXPECT_TRUE(is_file_inside(file.parent_path() / percent_decoded(link), dir_ / "runs"))
          << page << ": " << link;
    }
    for (const std::string& svg : inline_svgs(html)) {
      for (const std::string& problem : SvgChecker::check(svg))
        ADD_FAILURE() << page << ": " << problem;
    }
  }
  EXPECT_GE(links, 5u);  // a report of each comparison folder
  const std::string index = read_file(dir_ / "runs" / "index.html");
  EXPECT_NE(index.find("href=\"./javascript%3Avoid%28window.pwned%3D1%29/report.html\""),
            std::string::npos);
  EXPECT_NE(index.find("href=\"./not-utf8-%FF/report.html\""), std::string::npos);
  EXPECT_NE(index.find(">not-utf8-\xef\xbf\xbd</a>"), std::string::npos);  // shown as U+FFFD
  // The labels, in the table and in the overlay's legend, with U+FFFD in place of what is hidden.
  EXPECT_NE(index.find("Adam\xef\xbf\xbd"
                       "evil\xef\xbf\xbd\xef\xbf\xbd<"),
            std::string::npos);
  EXPECT_NE(index.find("Adam\xef\xbf\xbd"
                       "evil\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd<"),
            std::string::npos);
  // The comparison folders' x-distance and the learning folder's test loss.
  EXPECT_EQ(inline_svgs(index).size(), 2u);
}

TEST_F(ReportPages, TypedFolderNamesWithBidirectionalControlsOrNoncharactersAreRefused) {
  for (const auto& [name, problem] : std::vector<std::pair<std::string, std::string>>{
           {"a\xe2\x80\xae"
            "b",
            "contains the bidirectional control U+202E at byte 1"},
           {"a\xe2\x81\xa6"
            "b",
            "contains the bidirectional control U+2066 at byte 1"},
           {"a\xef\xbf\xbf"
            "b",
            "contains the noncharacter U+FFFF at byte 1"},
           {"a\xef\xbf\xbe"
            "b",
            "contains the noncharacter U+FFFE at byte 1"}}) {
    const physgrad::testing::Outcome outcome = run("run comparison --iters 2 --out '" + name + "'");
    EXPECT_EQ(outcome.exit_code, 2) << name;
    EXPECT_NE(outcome.err.find(problem), std::string::npos) << outcome.err;
    EXPECT_TRUE(fs::is_empty(dir_)) << name;
  }
  // In a config file as well; and U+2069 in a list value.
  const physgrad::testing::Outcome config =
      run("run comparison --config " + write_config("c.json", R"({"out": "r\u202db"})"));
  EXPECT_EQ(config.exit_code, 2);
  EXPECT_NE(config.err.find("--out: 'r"), std::string::npos) << config.err;
  EXPECT_NE(config.err.find("contains the bidirectional control U+202D at byte 1"),
            std::string::npos)
      << config.err;
  const physgrad::testing::Outcome list =
      run("run comparison --pg-inverse 'gn\xe2\x81\xa9' --out r");
  EXPECT_EQ(list.exit_code, 2);
  EXPECT_NE(list.err.find("contains the bidirectional control U+2069 at byte 2"), std::string::npos)
      << list.err;
  EXPECT_TRUE(fs::is_empty(dir_));
}

// Chromium loads the index and every report of the hostile runs in frames of one page, a copy
// of each page with a script added. The script logs the address every href and src resolves to
// (the browser's own reading of it) and the page's scripts and event-handler attributes, then
// clicks one link: the n-th, for the frame whose address ends in #n (one frame per link). A link
// to a local file (checked to be one inside runs/) is not followed; any other is — a javascript:
// address would run (the hostile one sets window.pwned), an address of another site would be
// asked for. Every request for anything but a file goes through a proxy that is a listening
// socket of this test (`--proxy-server`, loopback addresses not exempted), so a request that
// would leave the machine is seen; a canary request of the frame page shows that it sees them.
TEST_F(ReportPages, ChromiumRunsNoScriptAndAsksNoServerForHostileFolders) {
  if (!fs::exists(kChromium)) GTEST_SKIP() << "no " << kChromium << " (make test installs it)";
  ASSERT_TRUE(make_hostile_index());
  const std::vector<std::string> pages = hostile_pages();
  std::string frames = "<img src=\"http://canary.physgrad.invalid/canary.png\">\n";
  std::vector<std::string> expected;  // the last message of each frame
  for (std::size_t k = 0; k < pages.size(); ++k) {
    std::string html = read_file(dir_ / "runs" / pages[k]);
    const std::string script =
        "<script>window.addEventListener('load', () => {"
        "const frame = '" +
        std::to_string(k) +
        " ' + location.hash.slice(1);"
        "for (const e of document.querySelectorAll('[href],[src]')) {"
        "const raw = e.getAttribute('href') ?? e.getAttribute('src');"
        "console.log('physgrad-link ' + frame + ' ' + new URL(raw, document.baseURI).href); }"
        "const handlers = [...document.querySelectorAll('*')].filter("
        "e => [...e.attributes].some(a => a.name.toLowerCase().startsWith('on'))).length;"
        "console.log('physgrad-scripts ' + frame + ' ' + document.scripts.length + ' ' + handlers);"
        "const a = document.querySelectorAll('a')[Number(location.hash.slice(1))];"
        "if (a) { a.addEventListener('click', event => {"
        "if (a.protocol === 'file:') event.preventDefault(); }); a.click(); }"
        "setTimeout(() => console.log('physgrad-after ' + frame + ' ' +"
        "(window.pwned === undefined ? 'clean' : 'script-ran')), 1000); });</script>\n";
    html.replace(html.rfind("</body>"), 7, script + "</body>");
    const fs::path copy = dir_ / "runs" / pages[k];
    const std::string checked = "checked_" + copy.filename().string();
    std::ofstream(copy.parent_path() / checked) << html;
    const std::size_t anchors = count(html, "<a ");
    for (std::size_t n = 0; n < std::max<std::size_t>(anchors, 1); ++n) {
      frames +=
          "<iframe src=\"" +
          physgrad::local_href("runs/" + (fs::path(pages[k]).parent_path() / checked).string()) +
          "#" + std::to_string(n) + "\" width=\"600\" height=\"200\"></iframe>\n";
      expected.push_back(std::to_string(k) + " " + std::to_string(n) + " clean");
    }
  }
  std::ofstream(dir_ / "all.html") << "<!DOCTYPE html><html><body>\n"
                                   << frames << "</body></html>\n";
  Listener proxy;
  const fs::path log = dir_ / "chromium.log";
  ASSERT_EQ(run_chromium(dir_ / "all.html", dir_ / "chromium-profile", log,
                         "--proxy-server=http://127.0.0.1:" + std::to_string(proxy.port()) +
                             " --proxy-bypass-list='<-loopback>'"),
            0)
      << read_file(log);
  std::vector<std::string> requests = proxy.stop();
  std::erase_if(requests,
                [](const std::string& r) { return is_browser_service(requested_host(r)); });
  std::string asked;
  for (const std::string& r : requests) asked += r + "\n";
  EXPECT_EQ(requests.size(), 1u) << "requests other than the canary's:\n" << asked;
  EXPECT_EQ(requests.empty() ? "" : requested_host(requests[0]), "canary.physgrad.invalid")
      << "the proxy saw no canary: " << asked;

  const std::string console = read_file(log);
  std::size_t links = 0;
  for (const std::string& message : console_messages(console, "link")) {
    const std::size_t space = message.find(' '), second = message.find(' ', space + 1);
    expect_local_file(message.substr(second + 1), pages.at(std::stoul(message.substr(0, space))));
    ++links;
  }
  EXPECT_GE(links, 5u) << console;
  for (const std::string& message : console_messages(console, "scripts")) {
    EXPECT_EQ(message.substr(message.find(' ', message.find(' ') + 1) + 1), "1 0")
        << message << ": scripts and event handlers beyond the one added";
  }
  std::vector<std::string> after = console_messages(console, "after");
  std::sort(after.begin(), after.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(after, expected) << "a frame whose link ran a script or left the page (no message):\n"
                             << console;
}

// The index compares folders of one experiment by the metric its message compares: sin-rotation
// by the x-distance at ξ = 32 only, with the options a folder changed and the rules' colours.
TEST_F(ReportPages, TheIndexComparesFoldersByTheMessageMetric) {
  const std::string args =
      "run sin-rotation --xi 1,32 --iters 60 --train-size 100 --test-size 20 --eval-every 20";
  ASSERT_EQ(run(args + " --out runs/a").exit_code, 0);
  ASSERT_EQ(run(args + " --lr 0.01 --out runs/b").exit_code, 0);
  ASSERT_EQ(run("report runs").exit_code, 0);
  const std::string index = read_file(dir_ / "runs" / "index.html");
  const std::size_t section = index.find("<h2>sin-rotation</h2>");
  ASSERT_NE(section, std::string::npos);
  // Each folder's message sentence, then the table by the metric it names.
  EXPECT_NE(index.find("<p>a: At ξ = 32, ", section), std::string::npos);
  EXPECT_NE(index.find("<p>b: At ξ = 32, ", section), std::string::npos);
  EXPECT_NE(index.find("<th>final x-distance to the nearest exact solution</th>", section),
            std::string::npos);
  // Options: what differs from the defaults (iters, sizes, eval-every; b also lr), per folder.
  EXPECT_NE(index.find("<td data-h=\"options\">eval-every = 20, iters = 60, test-size = 20, "
                       "train-size = 100</td>"),
            std::string::npos);
  EXPECT_NE(index.find("<td data-h=\"options\">eval-every = 20, iters = 60, lr = 0.01, "
                       "test-size = 20, "
                       "train-size = 100</td>"),
            std::string::npos);
  // Only the ξ = 32 runs are compared, each rule in its colour, one best per folder.
  const std::string table = index.substr(section, index.find("<h2>Every run</h2>") - section);
  EXPECT_EQ(table.find("ξ=1)"), std::string::npos);
  EXPECT_NE(table.find("SIP (ξ=32)"), std::string::npos);
  EXPECT_NE(table.find("<span class=\"swatch\" style=\"background:#000000\"></span>SIP (ξ=32)"),
            std::string::npos);  // SIP's colour in the catalogue
  std::size_t best = 0;
  const std::string best_cell = "<td data-h=\"× best\">best</td>";
  for (std::size_t at = table.find(best_cell); at != std::string::npos;
       at = table.find(best_cell, at + 1)) {
    ++best;
  }
  EXPECT_EQ(best, 2u);
  // The overlays draw the x-distance of the six compared runs against updates and against
  // training time, each axis labelled with what it plots.
  const std::vector<std::string> svgs = inline_svgs(table);
  ASSERT_EQ(svgs.size(), 2u);
  for (const std::string& svg : svgs) {
    EXPECT_NE(svg.find(">x-distance to the nearest exact solution</text>"), std::string::npos);
    EXPECT_NE(svg.find("b: Adam (ξ=32)"), std::string::npos);
    EXPECT_EQ(svg.find("ξ=1)"), std::string::npos);
  }
  EXPECT_NE(svgs[0].find(">updates (iterations)</text>"), std::string::npos);
  EXPECT_NE(svgs[1].find(">training time (s, evaluations excluded)</text>"), std::string::npos);
}

TEST_F(ReportPages, AFolderWithAFieldOfTheWrongTypeIsLeftOutWithAOneLineWarning) {
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
TEST_F(ReportPages, LargeFilesAreReadInBoundedTimeAndMemoryAndWhatIsLeftOutIsSaid) {
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
  const std::vector<std::string> warnings = {
      "'runs/huge/metrics.csv': is 33554433 bytes, more than the 33554432 allowed; its loss "
      "curves are not drawn",
      "'runs/long/metrics.csv': 200100 rows, only the first 200000 are drawn",
      "'runs/many/summary.json': 12000 runs, only the first 10000 are listed",
      "'runs/seeds/metrics.csv': more than 256 curves (label and seed), the 44 rows of the "
      "others are not drawn",
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

}  // namespace
