// The interactive comparison as a reader uses it: headless Chromium shows the index and a report
// in frames 420 × 900 px and 1280 × 800 px, with a script added (allowed by its hash) that works
// each control and logs "physgrad-compare FRAME CONTROL ok|fail DETAIL": picking a run (one path
// fewer), the metric (other path data), hiding a run by its legend entry, the log toggle (the
// axis label), per second (the x label), smoothing (other path data), zoom by the wheel and its
// reset, the readout (a value per shown run) and the CSV (its header and each shown run).
#include <gtest/gtest.h>

#include <algorithm>
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

constexpr const char* kControlScript = R"js(
window.addEventListener('load', () => {
const frame = location.hash.slice(1);
const log = (name, ok, detail) => console.log('physgrad-compare ' + frame + ' ' + name + ' ' + (ok ? 'ok' : 'fail') + ' ' + detail);
const paths = () => [...document.querySelectorAll('#pg-compare path.pg-run')];
const ds = () => paths().map(p => p.getAttribute('d')).join('|');
const text = id => document.getElementById(id).textContent;
const fire = (e, type) => e.dispatchEvent(new Event(type));
const n0 = paths().length, d0 = ds();
log('drawn', n0 > 0, n0);
const metric = document.getElementById('pg-metric');
if (metric.options.length > 1) { metric.selectedIndex = 1; fire(metric, 'change');
  log('metric', ds() !== d0, metric.value); metric.selectedIndex = 0; fire(metric, 'change'); }
const drawn = paths()[0].getAttribute('data-run');
const pick = document.querySelector('.pg-pick[data-run="' + drawn + '"]');
pick.checked = false; fire(pick, 'change');
log('select', paths().length === n0 - 1, paths().length);
pick.checked = true; fire(pick, 'change');
document.querySelector('.pg-entry[data-run="' + drawn + '"]').click();
log('hide', paths().length === n0 - 1 && document.querySelectorAll('.pg-off').length === 1, paths().length);
document.querySelector('.pg-entry[data-run="' + drawn + '"]').click();
const y0 = text('pg-ylabel'), log_box = document.getElementById('pg-log');
log_box.checked = true; fire(log_box, 'change');
log('log', text('pg-ylabel') !== y0 && text('pg-ylabel').includes('log'), text('pg-ylabel'));
log_box.checked = false; fire(log_box, 'change');
const x0 = text('pg-xlabel'); document.getElementById('pg-x').click();
log('per-second', text('pg-xlabel') !== x0, text('pg-xlabel'));
document.getElementById('pg-x').click();
const d1 = ds(), slider = document.getElementById('pg-smooth');
slider.value = '0.9'; fire(slider, 'input');
log('smoothing', ds() !== d1, slider.value);
slider.value = '0'; fire(slider, 'input');
const svg = document.querySelector('#pg-compare svg'), r = svg.getBoundingClientRect();
svg.dispatchEvent(new WheelEvent('wheel', {deltaY: -100, clientX: r.left + r.width / 2, clientY: r.top + r.height / 2, cancelable: true}));
log('zoom', ds() !== d1, '');
svg.dispatchEvent(new MouseEvent('dblclick'));
log('reset', ds() === d1, '');
svg.dispatchEvent(new MouseEvent('mousemove', {clientX: r.left + r.width / 2, clientY: r.top + r.height / 2}));
log('readout', document.querySelector('.pg-readout').textContent.split(' · ').length === n0 + 1, document.querySelector('.pg-readout').textContent.length);
const csv = window.physgradCompareCsv().split('\n');
const seen = new Set(csv.slice(1).filter(l => l).map(l => l.split(',').slice(-3)[0]));
log('csv', csv[0].startsWith('group,label,seed,run,') && seen.size === n0, csv[0] + ' ' + seen.size);
log('clean', window.pwned === undefined && document.querySelectorAll('#pg-compare img,#pg-compare script').length === 0, '');
});
)js";

TEST_F(ReportPages, ChromiumWorksEveryControlOfTheInteractiveComparison) {
  if (!fs::exists(kChromium)) GTEST_SKIP() << "no " << kChromium << " (make test installs it)";
  ASSERT_TRUE(make_reports());
  const std::vector<std::string> pages = {"index.html",
                                          physgrad::testing::cases().front().folder +
                                              "/report.html"};
  const std::vector<int> widths = {420, 1280}, heights = {900, 800};
  std::string frames;
  for (std::size_t k = 0; k < pages.size(); ++k) {
    const std::string html = read_file(dir_ / pages[k]);
    ASSERT_NE(html.find("id=\"pg-compare-data\""), std::string::npos) << pages[k];
    const fs::path page = fs::path(pages[k]).parent_path() / "controls.html";
    std::ofstream(dir_ / page) << physgrad::testing::with_added_script(html, kControlScript);
    for (std::size_t w = 0; w < widths.size(); ++w) {
      frames += "<iframe src=\"" + page.string() + "#" + std::to_string(k * widths.size() + w) +
                "\" width=\"" + std::to_string(widths[w]) + "\" height=\"" +
                std::to_string(heights[w]) + "\"></iframe>\n";
    }
  }
  std::ofstream(dir_ / "all.html") << "<!DOCTYPE html><html><body>\n" << frames << "</body></html>\n";
  const fs::path log = dir_ / "chromium.log";
  ASSERT_EQ(run_chromium(dir_ / "all.html", dir_ / "chromium-profile", log), 0) << read_file(log);
  const std::vector<std::string> messages = console_messages(read_file(log), "compare");
  const std::vector<std::string> controls = {"drawn", "select", "hide", "log", "per-second",
                                             "smoothing", "zoom", "reset", "readout", "csv",
                                             "clean"};
  for (std::size_t frame = 0; frame < pages.size() * widths.size(); ++frame) {
    for (const std::string& control : controls) {
      const std::string ok = std::to_string(frame) + " " + control + " ok";
      const bool seen = std::any_of(messages.begin(), messages.end(), [&](const std::string& m) {
        return m.rfind(ok, 0) == 0;
      });
      EXPECT_TRUE(seen) << pages[frame / widths.size()] << " at " << widths[frame % widths.size()]
                        << " px: " << control << " did not work";
    }
  }
  for (const std::string& m : messages) EXPECT_EQ(m.find(" fail "), std::string::npos) << m;
}

}  // namespace
