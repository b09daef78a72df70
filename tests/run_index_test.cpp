// The index of run folders (`physgrad report DIR`): each experiment compared by the metric its
// message compares, on its own axes; failed and unconverged runs counted apart from the medians
// and never ranked; the digits a median shows follow its spread; a run folder named index.html
// moves the page aside instead of ending it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "report_pages_fixture.hpp"

namespace {

using physgrad::testing::inline_svgs;
using physgrad::testing::read_file;
using physgrad::testing::ReportPages;
// The run folders of a test and their index.
class RunIndex : public ReportPages {};
namespace fs = std::filesystem;

using Row = std::map<std::string, std::string>;  // header → the cell's text

// The rows of the first table after `from` in `html`, each cell by its header (data-h), tags
// dropped.
std::vector<Row> table_rows(const std::string& html, std::size_t from) {
  std::vector<Row> rows;
  const std::size_t end = html.find("</table>", from);
  for (std::size_t tr = html.find("<tr><td", from); tr < end; tr = html.find("<tr><td", tr + 1)) {
    Row row;
    const std::size_t row_end = html.find("</tr>", tr);
    for (std::size_t td = html.find("<td data-h=\"", tr); td < row_end;
         td = html.find("<td data-h=\"", td + 1)) {
      const std::size_t name = td + 12, name_end = html.find('"', name);
      const std::size_t cell = html.find('>', name_end) + 1, cell_end = html.find("</td>", cell);
      std::string text;
      bool in_tag = false;
      for (const char c : html.substr(cell, cell_end - cell)) {
        if (c == '<') in_tag = true;
        if (!in_tag) text += c;
        if (c == '>') in_tag = false;
      }
      row[html.substr(name, name_end - name)] = text;
    }
    rows.push_back(row);
  }
  return rows;
}

// The row of `rows` whose cells hold `cells` (header → text), or an empty row.
Row row_with(const std::vector<Row>& rows, const Row& cells) {
  for (const Row& row : rows) {
    if (std::all_of(cells.begin(), cells.end(),
                    [&](const auto& c) { return row.contains(c.first) && row.at(c.first) == c.second; })) {
      return row;
    }
  }
  return {};
}

// The index compares folders of one experiment by the metric its message compares: sin-rotation
// by the x-distance at ξ = 32 only, with the options a folder changed and the rules' colours.
TEST_F(RunIndex, TheIndexComparesFoldersByTheMessageMetric) {
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
  // training time, each axis labelled with what it plots (the log y axis says so).
  const std::vector<std::string> svgs = inline_svgs(table);
  ASSERT_EQ(svgs.size(), 2u);
  for (const std::string& svg : svgs) {
    EXPECT_NE(svg.find(">x-distance to the nearest exact solution (log scale)</text>"),
              std::string::npos);
    EXPECT_NE(svg.find("b: Adam (ξ=32)"), std::string::npos);
    EXPECT_EQ(svg.find("ξ=1)"), std::string::npos);
  }
  EXPECT_NE(svgs[0].find(">updates (iterations)</text>"), std::string::npos);
  EXPECT_NE(svgs[1].find(">training time (s, evaluations excluded)</text>"), std::string::npos);
}

// A direct run of scaled-toy's kind written by hand: per rule four runs (α = 1, 10, 100, 1000)
// and how each ended, with the iterations it took.
nlohmann::json hand_run(const std::string& label, const std::string& id, double alpha,
                        int iterations, const std::string& termination) {
  return {{"label", label},         {"optimizer", id},
          {"params", {{"alpha", alpha}}}, {"initial", {{"loss", 1.0}}},
          {"final", {{"loss", termination == "converged" ? 1e-12 : 0.5}}},
          {"iterations", iterations}, {"epochs", nullptr},
          {"wall_seconds", 1e-4},     {"termination", termination}};
}

// Medians 1e-10 apart (relative) share rank 1 and "best"; a direct run that hit its iteration
// limit with the loss above its start is "diverging", not "did not converge".
TEST_F(RunIndex, NearTiesShareARankAndADivergingRunIsNamedSo) {
  const auto direct_run = [](const std::string& label, const std::string& id, double loss,
                             const std::string& termination) {
    return nlohmann::json{{"label", label},          {"optimizer", id},
                          {"params", nlohmann::json::object()},
                          {"initial", {{"loss", 1.0}}}, {"final", {{"loss", loss}}},
                          {"iterations", 50},        {"epochs", nullptr},
                          {"wall_seconds", 1e-4},    {"termination", termination}};
  };
  const auto write = [&](const std::string& name, const nlohmann::json& runs,
                         const std::string& metric) {
    const nlohmann::json summary = {
        {"experiment", "hand-direct"},
        {"runs", runs},
        {"message", {{"figure", "x.svg"}, {"sentence", "Hand."}, {"metric", metric},
                     {"metric_text", metric == "loss" ? "final loss" : "iterations"},
                     {"labels", {}}}}};
    fs::create_directories(dir_ / "runs" / name);
    std::ofstream(dir_ / "runs" / name / "summary.json") << summary.dump();
  };
  write("ties",
        {direct_run("PG (analytic inverse)", "pg", 1e-3, "max_iterations"),
         direct_run("PG (L-BFGS inverse)", "pg", 1e-3 * (1 - 1e-10), "max_iterations"),
         direct_run("GD", "gd", 2e-3, "max_iterations")},
        "loss");
  write("costs",
        {direct_run("Newton", "newton", 1e-12, "converged"),
         direct_run("GD", "gd", 7e190, "max_iterations"),
         direct_run("IG", "ig", 0.5, "max_iterations")},
        "iterations");
  const physgrad::testing::Outcome index = run("report runs");
  ASSERT_EQ(index.exit_code, 0) << index.err;
  const std::string html = read_file(dir_ / "runs" / "index.html");
  const std::vector<Row> ties = table_rows(html, html.find("<th>final loss</th>"));
  for (const char* pg : {"PG (analytic inverse)", "PG (L-BFGS inverse)"}) {
    const Row row = row_with(ties, {{"run folder", "ties"}, {"rule", pg}});
    EXPECT_EQ(row.at("rank"), "1") << pg;
    EXPECT_EQ(row.at("× best"), "best") << pg;
  }
  EXPECT_EQ(row_with(ties, {{"run folder", "ties"}, {"rule", "GD"}}).at("rank"), "3");
  const std::vector<Row> costs = table_rows(html, html.find("<th>iterations</th>"));
  EXPECT_EQ(row_with(costs, {{"run folder", "costs"}, {"rule", "GD"}}).at("apart"),
            "1 of 1 diverging (loss above its start)");
  EXPECT_EQ(row_with(costs, {{"run folder", "costs"}, {"rule", "IG"}}).at("apart"),
            "1 of 1 did not converge");
}

// A learning folder whose message compares the "median final test loss at λ = 1" draws its
// curves over updates as the "test loss at λ = 1": a curve is neither a median of finals nor final.
TEST_F(RunIndex, CurvesOverUpdatesAreNotLabelledAsFinals) {
  nlohmann::json runs = nlohmann::json::array();
  std::string csv = "label,optimizer,seed,iteration,wall_seconds,test_loss\n";
  for (const char* rule : {"adam", "hig"}) {
    const std::string label = rule == std::string("adam") ? "Adam" : "HIG";
    runs.push_back({{"label", label}, {"optimizer", rule}, {"params", {{"seed", 0}}},
                    {"initial", {{"loss", 1.0}}}, {"final", {{"loss", 0.1}, {"test_loss", 0.1}}},
                    {"iterations", 20}, {"epochs", 1}, {"wall_seconds", 0.1},
                    {"termination", "max_iterations"}});
    for (int k = 0; k <= 2; ++k) {
      csv += label + "," + rule + ",0," + std::to_string(10 * k) + "," + std::to_string(0.01 * k) +
             "," + std::to_string(1.0 / (1 + k)) + "\n";
    }
  }
  const nlohmann::json summary = {
      {"experiment", "hand-learning"},
      {"runs", runs},
      {"message", {{"figure", "x.svg"}, {"sentence", "Hand."}, {"metric", "test_loss"},
                   {"metric_text", "median final test loss at λ = 1"}, {"labels", {}}}}};
  fs::create_directories(dir_ / "runs" / "learn");
  std::ofstream(dir_ / "runs" / "learn" / "summary.json") << summary.dump();
  std::ofstream(dir_ / "runs" / "learn" / "metrics.csv") << csv;
  const physgrad::testing::Outcome index = run("report runs");
  ASSERT_EQ(index.exit_code, 0) << index.err;
  const std::string html = read_file(dir_ / "runs" / "index.html");
  const std::vector<std::string> svgs = inline_svgs(html);
  ASSERT_FALSE(svgs.empty());
  for (const std::string& svg : svgs) {
    EXPECT_EQ(svg.find("median final test loss"), std::string::npos);
    EXPECT_TRUE(svg.find(">test loss at λ = 1</text>") != std::string::npos ||
                svg.find(">test loss at λ = 1 (log scale)</text>") != std::string::npos);
  }
}

// A folder whose run failed at lr 10 (its test loss climbing to 1e105 before the failure) beside
// a folder of healthy runs: the failed curve does not stretch the index figure's axis (no tick
// beyond 1e+02), and two healthy rules whose finals differ (SGD 0.777, Adam 0.873) are not said to
// coincide.
TEST_F(RunIndex, AFailedRunNeitherStretchesTheAxisNorMakesHealthyCurvesCoincide) {
  const auto write_folder = [this](const std::string& name,
                                   const std::vector<std::tuple<std::string, std::string, double,
                                                                std::vector<double>>>& rules) {
    nlohmann::json runs = nlohmann::json::array();
    std::string csv = "label,optimizer,seed,lr,iteration,wall_seconds,test_loss\n";
    for (const auto& [label, id, lr, losses] : rules) {
      const bool failed = losses.back() > 1e10;
      runs.push_back({{"label", label}, {"optimizer", id}, {"params", {{"seed", 0}, {"lr", lr}}},
                      {"initial", {{"loss", losses.front()}}},
                      {"final", {{"loss", losses.back()}, {"test_loss", losses.back()}}},
                      {"iterations", 10 * (losses.size() - 1)}, {"epochs", 1},
                      {"wall_seconds", 0.1},
                      {"termination", failed ? "numerical_failure" : "max_iterations"}});
      for (std::size_t k = 0; k < losses.size(); ++k) {
        csv += label + "," + id + ",0," + std::to_string(lr) + "," + std::to_string(10 * k) + "," +
               std::to_string(0.01 * static_cast<double>(k)) + "," + std::to_string(losses[k]) +
               "\n";
      }
    }
    const nlohmann::json summary = {
        {"experiment", "hand-learning"},
        {"runs", runs},
        {"message", {{"figure", "x.svg"}, {"sentence", "Hand."}, {"metric", "test_loss"},
                     {"metric_text", "final test loss"}, {"labels", {}}}}};
    fs::create_directories(dir_ / "runs" / name);
    std::ofstream(dir_ / "runs" / name / "summary.json") << summary.dump();
    std::ofstream(dir_ / "runs" / name / "metrics.csv") << csv;
  };
  write_folder("healthy", {{"SGD", "sgd", 0.01, {1.0, 0.9, 0.777}},
                           {"Adam", "adam", 0.001, {1.0, 0.95, 0.873}}});
  write_folder("lr10", {{"Adam (lr 10)", "adam", 10, {1.0, 1e50, 1e105}}});
  const physgrad::testing::Outcome index = run("report runs");
  ASSERT_EQ(index.exit_code, 0) << index.err;
  const std::string html = read_file(dir_ / "runs" / "index.html");
  const std::vector<std::string> svgs = inline_svgs(html);
  ASSERT_FALSE(svgs.empty());
  EXPECT_NE(html.find("ends off scale at 1e+105"), std::string::npos);
  for (const std::string& svg : svgs) {
    // Every power of ten the figure prints is a tick, except the failed curve's own end label.
    for (std::size_t at = svg.find("e+"); at != std::string::npos; at = svg.find("e+", at + 2)) {
      const std::string before = svg.substr(at > 20 ? at - 20 : 0, at > 20 ? 20 : at);
      if (before.find("off scale at ") != std::string::npos) continue;
      EXPECT_LE(std::atoi(svg.c_str() + at + 2), 2) << before << svg.substr(at, 8);
    }
    EXPECT_EQ(svg.find("SGD (coincides with Adam"), std::string::npos);
    EXPECT_EQ(svg.find("coincides with SGD"), std::string::npos);
  }
}

// Folders a run started and did not finish (config.json, no summary.json) are counted beside
// the shown ones, with how many hold a checkpoint to resume from.
TEST_F(RunIndex, TheFolderCountNamesUnfinishedAndResumableFolders) {
  const nlohmann::json summary = {
      {"experiment", "hand-direct"},
      {"runs", {{{"label", "GD"}, {"optimizer", "gd"}, {"params", nlohmann::json::object()},
                 {"initial", {{"loss", 1.0}}}, {"final", {{"loss", 0.5}}}, {"iterations", 5},
                 {"epochs", nullptr}, {"wall_seconds", 1e-4}, {"termination", "max_iterations"}}}}};
  fs::create_directories(dir_ / "runs" / "done");
  std::ofstream(dir_ / "runs" / "done" / "summary.json") << summary.dump();
  for (const char* killed : {"killed-a", "killed-b"}) {
    fs::create_directories(dir_ / "runs" / killed);
    std::ofstream(dir_ / "runs" / killed / "config.json") << "{}";
  }
  std::ofstream(dir_ / "runs" / "killed-b" / "checkpoint.pgc") << "x";
  fs::create_directories(dir_ / "runs" / "not-a-run");
  const physgrad::testing::Outcome index = run("report runs");
  ASSERT_EQ(index.exit_code, 0) << index.err;
  const std::string html = read_file(dir_ / "runs" / "index.html");
  EXPECT_NE(html.find("1 run folders (and 2 unfinished, not shown"), std::string::npos);
  EXPECT_NE(html.find("1 of them with a checkpoint, resumable"), std::string::npos);
}

// Folders of converged, diverged, failed and unconverged direct runs: the index compares them
// by iterations to the tolerance, counts the runs that failed or did not converge apart from the
// median, never ranks a rule with any, ranks ties alike, and shows the digits the spread allows.
TEST_F(RunIndex, TheIndexRanksDirectRulesByTheirMessageAndNeverRanksFailedRuns) {
  nlohmann::json runs = nlohmann::json::array();
  const std::vector<double> alphas = {1, 10, 100, 1000};
  const auto add_rule = [&](const std::string& label, const std::string& id,
                            const std::vector<std::pair<int, std::string>>& ends) {
    for (std::size_t k = 0; k < ends.size(); ++k) {
      runs.push_back(hand_run(label, id, alphas[k], ends[k].first, ends[k].second));
    }
  };
  const std::string c = "converged";
  add_rule("GD", "gd", {{10, c}, {30, c}, {77, "numerical_failure"}, {20, c}});
  add_rule("Newton", "newton", {{2, c}, {2, c}, {3, c}, {3, c}});
  add_rule("BFGS", "bfgs", {{5, c}, {6, c}, {7, c}, {8, c}});
  add_rule("L-BFGS", "lbfgs", {{6, c}, {5, c}, {8, c}, {7, c}});
  add_rule("IG", "ig", {{4, c}, {4, c}, {300, "max_iterations"}, {300, "max_iterations"}});
  add_rule("Levenberg-Marquardt", "lm",
           {{9, "diverged"}, {9, "diverged"}, {9, "diverged"}, {9, "diverged"}});
  const nlohmann::json summary = {
      {"experiment", "scaled-toy"},
      {"runs", runs},
      {"message", {{"figure", "iterations_vs_alpha.svg"}, {"sentence", "Newton needs the fewest."},
                   {"metric", "iterations"},
                   {"metric_text", "iterations to the tolerance, over every α"}, {"labels", {}}}}};
  fs::create_directories(dir_ / "runs" / "hand");
  std::ofstream(dir_ / "runs" / "hand" / "summary.json") << summary.dump();
  // And two real ones: scaled-toy, where GD and Momentum fail at α = 100 and 1000, and
  // time-reversal, where PG with the IG inverse fails and some rules end unconverged.
  ASSERT_EQ(run("run scaled-toy --iters 200 --out runs/scaled").exit_code, 0);
  ASSERT_EQ(run("run time-reversal --iters 20 --out runs/time").exit_code, 0);
  const physgrad::testing::Outcome index = run("report runs");
  ASSERT_EQ(index.exit_code, 0) << index.err;
  const std::string html = read_file(dir_ / "runs" / "index.html");
  const std::size_t section = html.find("<h2>scaled-toy</h2>");
  ASSERT_NE(section, std::string::npos);
  EXPECT_NE(html.find("<p>hand: Newton needs the fewest.</p>", section), std::string::npos);
  EXPECT_NE(html.find("<th>iterations to the tolerance, over every α</th>", section),
            std::string::npos);
  const std::vector<Row> rows = table_rows(html, section);
  const std::string metric = "iterations to the tolerance, over every α";
  const auto hand = [&](const std::string& rule) {
    return row_with(rows, {{"run folder", "hand"}, {"rule", rule}});
  };
  EXPECT_EQ(hand("Newton")[metric], "2.5 (2–3)");
  EXPECT_EQ(hand("Newton")["rank"], "1");
  EXPECT_EQ(hand("Newton")["× best"], "best");
  // BFGS and L-BFGS tie: one rank, the next rank skipped; × best with two digits (the spread).
  for (const char* tie : {"BFGS", "L-BFGS"}) {
    EXPECT_EQ(hand(tie)[metric], "6.5 (5–8)") << tie;
    EXPECT_EQ(hand(tie)["rank"], "2") << tie;
    EXPECT_EQ(hand(tie)["× best"], "2.6×") << tie;
  }
  // GD: the failed run apart, the median over the three that converged; not ranked.
  EXPECT_EQ(hand("GD")[metric], "20 (10–30)");
  EXPECT_EQ(hand("GD")["apart"], "1 of 4 failed");
  EXPECT_EQ(hand("GD")["rank"], "not ranked");
  EXPECT_EQ(hand("GD")["× best"], "–");
  EXPECT_EQ(hand("GD")["ended by"], "converged, numerical_failure");
  // IG: two runs that stopped at the iteration limit have no iterations to the tolerance.
  EXPECT_EQ(hand("IG")[metric], "4");
  EXPECT_EQ(hand("IG")["apart"], "2 of 4 did not converge");
  EXPECT_EQ(hand("IG")["rank"], "not ranked");
  // LM diverged every time: nothing to take a median of.
  EXPECT_EQ(hand("Levenberg-Marquardt")[metric], "–");
  EXPECT_EQ(hand("Levenberg-Marquardt")["apart"], "4 of 4 failed");
  EXPECT_EQ(hand("Levenberg-Marquardt")["rank"], "not ranked");
  // The real scaled-toy run, checked against its summary.json: per rule the runs that failed
  // and those that did not converge apart, the median of the others' iterations, and a rank only
  // for a rule with neither.
  const nlohmann::json real = nlohmann::json::parse(read_file(dir_ / "runs/scaled/summary.json"));
  std::map<std::string, std::vector<double>> counted;
  std::map<std::string, std::pair<int, int>> apart;  // failed, unconverged
  for (const nlohmann::json& r : real.at("runs")) {
    const std::string label = r.at("label"), end = r.at("termination");
    if (end == "numerical_failure" || end == "diverged") {
      ++apart[label].first;
    } else if (end != "converged") {
      ++apart[label].second;
    } else {
      counted[label].push_back(r.at("iterations").get<double>());
    }
  }
  std::size_t ranked = 0, best = 0, real_rows = 0;
  for (const Row& row : rows) {
    if (row.at("run folder") != "scaled") continue;
    ++real_rows;
    const std::string rule = row.at("rule");
    const auto [failed, unconverged] = apart[rule];
    const std::string of = " of " + row.at("runs");
    std::string expected = failed > 0 ? std::to_string(failed) + of + " failed" : "";
    if (unconverged > 0) {
      expected += (expected.empty() ? std::to_string(unconverged) + of : ", " +
                   std::to_string(unconverged)) + " did not converge";
    }
    EXPECT_EQ(row.at("apart"), expected) << rule;
    EXPECT_EQ(row.at("rank") == "not ranked", failed + unconverged > 0) << rule;
    std::vector<double> values = counted[rule];
    std::sort(values.begin(), values.end());
    if (values.empty()) {
      EXPECT_EQ(row.at(metric), "–") << rule;
    } else {
      const std::size_t n = values.size();
      const double median = n % 2 ? values[n / 2] : (values[n / 2 - 1] + values[n / 2]) / 2;
      EXPECT_NEAR(std::stod(row.at(metric)), median, 0.05 * median) << rule;
    }
    ranked += row.at("rank") != "not ranked";
    best += row.at("× best") == "best";
  }
  EXPECT_EQ(real_rows, 10u);
  EXPECT_GE(ranked, 5u);
  EXPECT_GE(best, 1u);
  // Its curves against iterations, never against wall time.
  const std::string scaled = html.substr(section, html.find("<h2>", section + 1) - section);
  ASSERT_EQ(inline_svgs(scaled).size(), 1u);
  EXPECT_NE(inline_svgs(scaled)[0].find(">iterations</text>"), std::string::npos);
  EXPECT_EQ(scaled.find("wall"), std::string::npos);
  // time-reversal: by simulator passes, on a simulator-passes axis; the failed PG not ranked.
  const std::size_t time = html.find("<h2>time-reversal</h2>");
  ASSERT_NE(time, std::string::npos);
  const std::vector<Row> time_rows = table_rows(html, time);
  const Row failed = row_with(time_rows, {{"rule", "PG (IG inverse)"}});
  ASSERT_FALSE(failed.empty());
  EXPECT_EQ(failed.at("apart"), "2 of 2 failed");
  EXPECT_EQ(failed.at("rank"), "not ranked");
  const std::string passes = html.substr(time, html.find("<h2>", time + 1) - time);
  ASSERT_EQ(inline_svgs(passes).size(), 1u);
  EXPECT_NE(inline_svgs(passes)[0].find(">simulator passes (forward, VJP, reversal)"),
            std::string::npos);
}

// A pretrained run (Adam for --pretrain iterations, then its rule) is marked ◆ where it switched:
// in the report's loss curves (with a hover title) and in the index's overlay by updates. Over two
// paired seeds, each rule's curve is the median of both and the index's row counts both runs.
TEST_F(RunIndex, APretrainedRunIsMarkedWhereItSwitched) {
  ASSERT_EQ(run("run oscillators --train-size 32 --test-size 16 --iters 8 --eval-every 2 "
                "--batch 16 --pretrain 4 --seeds 2 --out runs/osc")
                .exit_code,
            0);
  ASSERT_EQ(run("report runs").exit_code, 0);
  const std::string figure = read_file(dir_ / "runs" / "osc" / "loss_vs_time_paper.svg");
  for (const char* rule : {"Adam→Gauss-Newton", "Adam→HIG"}) {
    EXPECT_NE(figure.find("<g class=\"mark\"><title>" + std::string(rule) +
                          " (paper), median of 2: switched from Adam after iteration 4</title>"),
              std::string::npos)
        << rule;
  }
  EXPECT_NE(figure.find("HIG (paper), median of 2"), std::string::npos);
  const std::string index = read_file(dir_ / "runs" / "index.html");
  EXPECT_NE(index.find("<td data-h=\"runs\">2</td>"), std::string::npos);
  EXPECT_EQ(index.find("<td data-h=\"runs\">1</td>"), std::string::npos);
  const std::vector<std::string> overlays = inline_svgs(index.substr(index.find("<h2>oscillators")));
  ASSERT_GE(overlays.size(), 2u);
  EXPECT_NE(overlays[0].find(">updates (iterations)</text>"), std::string::npos);
  EXPECT_NE(overlays[0].find(": switched from Adam after 4</title>"), std::string::npos);
  EXPECT_NE(overlays[0].find("(◆ switched from Adam after 4)"), std::string::npos);
}

// Integer settings and parameters read in full on both pages: seed 12345 was shown as
// "1.234e+04", which is 12340.
TEST_F(RunIndex, IntegersReadInFullOnTheReportAndTheIndex) {
  ASSERT_EQ(run("run oscillators --train-size 32 --test-size 16 --iters 8 --eval-every 2 "
                "--batch 16 --pretrain 4 --seeds 1 --seed 12345 --out runs/osc")
                .exit_code,
            0);
  ASSERT_EQ(run("report runs").exit_code, 0);
  const fs::path runs = dir_ / "runs";
  for (const fs::path& page : {runs / "osc" / "report.html", runs / "index.html"}) {
    const std::string html = read_file(page);
    EXPECT_NE(html.find("seed = 12345"), std::string::npos) << page;
    EXPECT_EQ(html.find("1.234e+04"), std::string::npos) << page;
  }
}

// A run folder may be named index.html: the page then takes the next free name, index-2.html,
// and the folder is listed like any other.
TEST_F(RunIndex, ARunFolderNamedIndexHtmlMovesThePageAside) {
  ASSERT_EQ(run("run comparison --iters 2 --out runs/index.html").exit_code, 0);
  ASSERT_EQ(run("run comparison --iters 3 --out runs/other").exit_code, 0);
  const physgrad::testing::Outcome outcome = run("report runs");
  ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
  EXPECT_EQ(outcome.out, "index of 2 run folders: runs/index-2.html\n");
  EXPECT_TRUE(fs::is_directory(dir_ / "runs" / "index.html"));
  EXPECT_TRUE(fs::exists(dir_ / "runs" / "index.html" / "report.html"));
  const std::string index = read_file(dir_ / "runs" / "index-2.html");
  EXPECT_NE(index.find("href=\"./index.html/report.html\""), std::string::npos);
  EXPECT_NE(index.find("href=\"./other/report.html\""), std::string::npos);
  // A second report finds index-2.html a regular file of its own and writes it again.
  ASSERT_EQ(run("report runs").exit_code, 0);
  EXPECT_FALSE(fs::exists(dir_ / "runs" / "index-3.html"));
}

TEST_F(RunIndex, ReportOfAFolderWithoutRunFoldersIsAOneLineError) {
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
  // A metrics.csv that is a FIFO leaves out the folder's curves, named
  fs::create_directories(dir_ / "fifo-metrics" / "a");
  std::ofstream(dir_ / "fifo-metrics" / "a" / "summary.json")
      << R"({"experiment": "hig-toy", "runs": []})";
  ASSERT_EQ(::mkfifo((dir_ / "fifo-metrics" / "a" / "metrics.csv").c_str(), 0600), 0);
  const physgrad::testing::Outcome metrics = run("report fifo-metrics");
  EXPECT_EQ(metrics.exit_code, 0);
  // and once more by the interactive comparison, which leaves out its runs.
  EXPECT_EQ(metrics.err,
            "physgrad: warning: report: 'fifo-metrics/a/metrics.csv': is not a regular file (a "
            "FIFO); not in the interactive comparison\n"
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

}  // namespace
