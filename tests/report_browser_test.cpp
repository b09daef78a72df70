// Every experiment's report and the index of their folders as a reader sees them: headless
// Chromium shows each page in frames 420 × 900 px (a phone) and 1280 × 800 px (a laptop), with a
// script added that measures the laid-out page. At both no figure or table reaches past the
// viewport or hides part of itself behind a sideways scroll and each report's message sentence
// starts on the first screen; at 420 px every figure shows its narrow layout, at 1280 px its
// wide one; at both, no figure is drawn out of its shape, no text in a figure is
// below 11 px (scaled either way) and every rule in each figure (each
// <g class="series">: its line and markers) has a visible mark that differs from every other
// rule's of its panel in colour, dashes or marker shape — and from one it coincides with in
// dashes or marker shape, colour aside.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "report_pages_fixture.hpp"

namespace {

using physgrad::testing::console_messages;
using physgrad::testing::kChromium;
using physgrad::testing::read_file;
using physgrad::testing::ReportPages;
using physgrad::testing::run_chromium;
namespace fs = std::filesystem;

// The script each framed page runs once laid out. It logs "physgrad-layout FRAME WIDTH RIGHT
// FIGURES TABLES SMALLEST SERIES WIDE NARROW STRETCHED HEIGHT TOP BOTTOM PAGE": the viewport's
// width, the right edge of the widest figure or table box, how many pixels of figures and of
// tables are hidden behind a sideways scroll, the smallest text in a figure (px), how many series
// it checked, how many figures show their wide and narrow layouts and how far (‰) the most
// stretched one is out of its shape, the viewport's height, where the message sentence starts
// and ends and the page's height; and "physgrad-problem FRAME …" for each rule without a mark of
// its own.
constexpr const char* kLayoutScript = R"js(
window.addEventListener('load', () => {
  const frame = location.hash.slice(1);
  const problem = text => console.log('physgrad-problem ' + frame + ' ' + text);
  let right = 0, figures = 0, tables = 0;
  for (const e of document.querySelectorAll('.table, .figure-scroll, figure')) {
    right = Math.max(right, e.getBoundingClientRect().right);
    const hidden = e.scrollWidth - e.clientWidth;
    if (e.classList.contains('table')) tables = Math.max(tables, hidden);
    else figures = Math.max(figures, hidden);
  }
  // Text size on screen: its font size times the smaller of the horizontal and the vertical
  // scale it is drawn at (a figure stretched one way only shrinks its text the other).
  let smallest = 1e9;
  for (const t of document.querySelectorAll('svg text')) {
    if (t.getBoundingClientRect().width === 0) continue;  // in the hidden layout
    const m = t.getScreenCTM();
    smallest = Math.min(smallest, parseFloat(getComputedStyle(t).fontSize) *
                                      Math.min(Math.hypot(m.a, m.b), Math.hypot(m.c, m.d)));
  }
  // How far a figure's shape on screen is from the shape of the layout it shows (‰).
  let stretched = 0;
  for (const root of document.querySelectorAll('.figure-scroll > div > svg')) {
    const shown = [...root.querySelectorAll('svg.pg-wide, svg.pg-narrow')].find(
        e => getComputedStyle(e).display !== 'none') || root;
    const box = shown.viewBox.baseVal, r = root.getBoundingClientRect();
    if (!box || box.height === 0 || r.height === 0) continue;
    const want = box.width / box.height;
    stretched = Math.max(stretched, Math.round(1000 * Math.abs(r.width / r.height - want) / want));
  }
  let wide = 0, narrow = 0;
  for (const svg of document.querySelectorAll('svg.pg-wide, svg.pg-narrow')) {
    if (getComputedStyle(svg).display === 'none') continue;
    if (svg.classList.contains('pg-wide')) ++wide; else ++narrow;
  }
  // The points of a line at 24 fractions of its length, in the page's pixels.
  const samples = line => {
    const n = line.getTotalLength(), m = line.getScreenCTM(), out = [];
    for (let k = 0; k <= 24; ++k) {
      const p = line.getPointAtLength(n * k / 24);
      out.push([m.a * p.x + m.c * p.y + m.e, m.b * p.x + m.d * p.y + m.f]);
    }
    return out;
  };
  const coincide = (a, b) => a.every((p, k) => Math.hypot(p[0] - b[k][0], p[1] - b[k][1]) < 1);
  let checked = 0;
  const panels = new Map();
  for (const g of document.querySelectorAll('g.series')) {
    const layout = g.closest('svg.pg-wide, svg.pg-narrow');
    if (layout && getComputedStyle(layout).display === 'none') continue;  // the other layout
    ++checked;
    const line = g.querySelector('.line'), marker = g.querySelector('.marker');
    const label = (g.closest('figure') || {}).id + ': ' + g.dataset.label;
    const drawn = line && line.getTotalLength() > 0;
    const marked = marker && (marker.getAttribute('d') || '').length > 0;
    if (!drawn && !marked) {  // allowed only where the figure says why
      if (!g.dataset.empty) problem(label + ' has no visible mark and no reason');
      continue;
    }
    const colour = getComputedStyle(drawn ? line : marker).stroke;
    const dashes = line ? (line.getAttribute('stroke-dasharray') || 'solid') : 'none';
    const shape = marked ? marker.dataset.shape : 'none';
    const panel = g.closest('g[transform]') || g.closest('svg');
    if (!panels.has(panel)) panels.set(panel, []);
    panels.get(panel).push({label, colour, dashes, shape, points: drawn ? samples(line) : null});
  }
  for (const series of panels.values()) {
    for (let i = 0; i < series.length; ++i) {
      for (let j = 0; j < i; ++j) {
        const a = series[i], b = series[j];
        const same_style = a.dashes === b.dashes && a.shape === b.shape;
        if (same_style && a.colour === b.colour) problem(a.label + ' looks like ' + b.label);
        else if (same_style && a.points && b.points && coincide(a.points, b.points))
          problem(a.label + ' hides ' + b.label + ' (same dashes and markers on one path)');
      }
    }
  }
  // Where the message sentence starts and ends on the page (px from its top; -1: none).
  const sentence = document.querySelector('p.message');
  const box = sentence ? sentence.getBoundingClientRect() : null;
  const top = box ? Math.round(box.top + scrollY) : -1;
  const bottom = box ? Math.round(box.bottom + scrollY) : -1;
  console.log('physgrad-layout ' + frame + ' ' + innerWidth + ' ' + Math.ceil(right) + ' ' +
              figures + ' ' + tables + ' ' + smallest.toFixed(2) + ' ' + checked + ' ' + wide +
              ' ' + narrow + ' ' + stretched + ' ' + innerHeight + ' ' + top + ' ' + bottom +
              ' ' + document.documentElement.scrollHeight);
});
)js";

struct Layout {
  int width = 0, right = 0, figures_hidden = 0, tables_hidden = 0;
  double smallest = 0;
  int series = 0, wide = 0, narrow = 0, stretched = 0;
  int height = 0, sentence_top = 0, sentence_bottom = 0, page_height = 0;
};

TEST_F(ReportPages, ChromiumShowsEveryPageAt420And1280PixelsWithAMarkForEveryRule) {
  if (!fs::exists(kChromium)) GTEST_SKIP() << "no " << kChromium << " (make test installs it)";
  ASSERT_TRUE(make_reports());
  std::vector<std::string> pages;
  for (const physgrad::testing::Case& c : physgrad::testing::cases()) {
    pages.push_back(c.folder + "/report.html");
  }
  pages.push_back("index.html");
  // A phone (420 × 900) and a laptop (1280 × 800).
  const std::vector<int> widths = {420, 1280}, heights = {900, 800};
  std::string frames;
  for (std::size_t k = 0; k < pages.size(); ++k) {
    std::string html = read_file(dir_ / pages[k]);
    html = physgrad::testing::with_added_script(std::move(html), kLayoutScript);
    const fs::path page = fs::path(pages[k]).parent_path() / "checked.html";
    std::ofstream(dir_ / page) << html;
    for (std::size_t w = 0; w < widths.size(); ++w) {
      frames += "<iframe src=\"" + page.string() + "#" + std::to_string(k * widths.size() + w) +
                "\" width=\"" + std::to_string(widths[w]) + "\" height=\"" +
                std::to_string(heights[w]) + "\"></iframe>\n";
    }
  }
  std::ofstream(dir_ / "all.html") << "<!DOCTYPE html><html><body>\n" << frames << "</body></html>\n";
  const fs::path log = dir_ / "chromium.log";
  ASSERT_EQ(run_chromium(dir_ / "all.html", dir_ / "chromium-profile", log), 0) << read_file(log);
  const std::string console = read_file(log);
  EXPECT_EQ(console.find("Error: <"), std::string::npos) << console;  // SVG errors
  for (const std::string& problem : console_messages(console, "problem")) {
    const std::size_t frame = std::stoul(problem.substr(0, problem.find(' ')));
    ADD_FAILURE() << pages[frame / widths.size()] << " at " << widths[frame % widths.size()]
                  << " px: " << problem.substr(problem.find(' ') + 1);
  }
  std::vector<Layout> layouts(pages.size() * widths.size());
  for (const std::string& message : console_messages(console, "layout")) {
    std::size_t frame = 0;
    Layout l;
    ASSERT_EQ(std::sscanf(message.c_str(), "%zu %d %d %d %d %lf %d %d %d %d %d %d %d %d", &frame,
                          &l.width, &l.right, &l.figures_hidden, &l.tables_hidden, &l.smallest,
                          &l.series, &l.wide, &l.narrow, &l.stretched, &l.height,
                          &l.sentence_top, &l.sentence_bottom, &l.page_height),
              14)
        << message;
    ASSERT_LT(frame, layouts.size());
    layouts[frame] = l;
  }
  int series = 0;
  for (std::size_t frame = 0; frame < layouts.size(); ++frame) {
    const Layout& l = layouts[frame];
    const std::string page = pages[frame / widths.size()];
    const int width = widths[frame % widths.size()];
    ASSERT_EQ(l.width, width) << page << " was not laid out at " << width << " px:\n" << console;
    // Text inside figures stays readable: at least 11 px (figures switch layout, never shrink).
    EXPECT_GE(l.smallest, 10.99) << page << " at " << width << " px";
    EXPECT_LE(l.stretched, 10) << page << " at " << width << " px: a figure drawn out of shape (‰)";
    series += l.series;
    EXPECT_LE(l.right, width) << page << " at " << width << " px: a box reaches past the page";
    EXPECT_LE(l.figures_hidden, 1) << page << " at " << width << " px: part of a figure is "
                                   << "behind a sideways scroll";
    std::printf("%s at %d px: page %d px tall, sentence at %d–%d px, tables hide %d px\n",
                page.c_str(), width, l.page_height, l.sentence_top, l.sentence_bottom,
                l.tables_hidden);
    // No table wider than its box, at either width (settings wrap).
    EXPECT_LE(l.tables_hidden, 1) << page << " at " << width << " px: part of a table is behind "
                                  << "a sideways scroll";
    // Every report's message sentence starts on the first screen.
    if (page != "index.html") {
      EXPECT_GE(l.sentence_top, 0) << page << ": no message sentence";
      EXPECT_LT(l.sentence_top, l.height) << page << " at " << width << " px: the message "
                                          << "sentence starts below the first screen";
    }
    if (width == 420) {
      EXPECT_EQ(l.wide, 0) << page << ": a figure shows its wide layout on a phone";
    } else {
      EXPECT_EQ(l.narrow, 0) << page << ": a figure shows its narrow layout on a laptop";
    }
  }
  EXPECT_GT(series, 400) << "few series checked: are the series hooks gone?";
}

}  // namespace
