// What the tests of the report pages share: the experiment runs whose reports they read, the
// <svg>s of a page, the text checks (UTF-8, links), headless Chromium on a page and its console
// messages, and the fixture that runs every case and writes the index of their folders.
#pragma once

#include <gtest/gtest.h>
#include <iconv.h>

#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "physgrad/report/compare_view.hpp"
#include "cli_fixture.hpp"
#include "svg_check.hpp"

namespace physgrad::testing {

struct Case {
  std::string folder, args;
  std::vector<std::string> figures;  // files that must be there (the message of the experiment)
};

inline const std::vector<Case>& cases() {
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
       {"x_distance_xi_32.svg", "landscape_xi_1.svg"}},
      {"heat-inverse",
       "run heat-inverse --n 8 --filters 4 --train-size 16 --test-size 4 --iters 10 "
       "--eval-every 5 --batch 4",
       {"x_loss_2d.svg", "sample_1.svg"}},
      {"heat-inverse-1d",
       "run heat-inverse --network mlp --dims 1 --n 16 --train-size 32 --test-size 8 --iters 20 "
       "--eval-every 5 --batch 8",
       {"reconstruction_1.svg", "x_loss_1d.svg"}},
      {"sip-poisson",
       "run sip-poisson --n 8 --filters 4 --train-size 8 --test-size 4 --iters 4 --eval-every 2 "
       "--batch 4",
       {"x_l1.svg"}},
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
inline std::vector<std::string> inline_svgs(const std::string& html) {
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


// Where `text` is not what a page may hold: a byte that is not UTF-8, a character XML forbids
// (C0 controls but tab, newline and CR; U+FFFE, U+FFFF) or a bidirectional control (U+202A–E,
// U+2066–9); empty when it is fine. Decoded by iconv, independently of the library.
inline std::string page_text_problem(const std::string& text) {
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
inline std::vector<std::string> link_attributes(const std::string& html) {
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
inline std::string percent_decoded(const std::string& text) {
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
inline bool is_file_inside(const fs::path& file, const fs::path& folder) {
  std::error_code error;
  const fs::path real = fs::canonical(file, error), root = fs::canonical(folder, error);
  if (error || !fs::is_regular_file(real, error)) return false;
  const std::string r = real.string(), f = root.string() + "/";
  return r.compare(0, f.size(), f) == 0;
}

// Debian's Chromium itself, without its launcher /usr/bin/chromium: the launcher adds Google's API
// keys and extensions, and with them sign-in and update requests of the browser's own.
inline constexpr const char* kChromium = "/usr/lib/chromium/chromium";

// Headless Chromium on `page` (a file), its console and errors in `log`; the exit status.
inline int run_chromium(const fs::path& page, const fs::path& profile, const fs::path& log,
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
// A page with `script` (its text, without the tags) added before </body>, allowed by the page's
// Content-Security-Policy (when it has one) by its hash beside the page's own script.
inline std::string with_added_script(std::string html, const std::string& script) {
  html.replace(html.rfind("</body>"), 7, "<script>" + script + "</script></body>");
  const std::string allowed = "script-src &#39;sha256-";
  const std::size_t at = html.find(allowed);
  if (at != std::string::npos) {
    html.replace(at, allowed.size(),
                 allowed + physgrad::sha256_base64(script) + "&#39; &#39;sha256-");
  }
  return html;
}

inline std::vector<std::string> console_messages(const std::string& log, const std::string& tag) {
  std::vector<std::string> found;
  const std::string start = "\"physgrad-" + tag + " ";
  for (std::size_t at = log.find(start); at != std::string::npos; at = log.find(start, at + 1)) {
    const std::size_t from = at + start.size(), end = log.find('"', from);
    found.push_back(log.substr(from, end - from));
  }
  return found;
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

}  // namespace physgrad::testing
