// The command-line tool end to end: bad input (flags or config file) gives one line on stderr
// naming the bad value, exit code 2 and no output; a good run writes the whole run folder; a
// saved config.json reproduces its run; describe shows the options.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>
#include <vector>

#include "cli_fixture.hpp"
#include "physgrad/io/csv.hpp"

namespace {

using physgrad::testing::Cli;
using physgrad::testing::Outcome;
using physgrad::testing::read_file;
namespace fs = std::filesystem;

TEST_F(Cli, BadInputIsOneLineExitTwoAndWritesNothing) {
  expect_rejected("run no-such-experiment", "'no-such-experiment'");
  expect_rejected("run scaled-toy --optimizers gd,sgdd", "'sgdd'");
  expect_rejected("run scaled-toy --lr -0.5", "-0.5");
  expect_rejected("run scaled-toy --lr 0", "'0'");
  expect_rejected("run scaled-toy --lr nan", "nan");
  expect_rejected("run scaled-toy --lr fast", "'fast'");
  expect_rejected("run scaled-toy --iters 0", "'0'");
  expect_rejected("run scaled-toy --iters 2.5", "'2.5'");
  // A number is its text and nothing around it.
  expect_rejected("run scaled-toy --iters '5 '", "--iters: '5 ' is not a whole number");
  expect_rejected("run scaled-toy --lr ' 0.5'", "--lr: ' 0.5' is not a number");
  expect_rejected("run scaled-toy --alpha 1,0", "'0'");
  expect_rejected("run scaled-toy --start 1,2,3", "got 3");
  expect_rejected("run scaled-toy --start 0,0", "(0, 0)");
  expect_rejected("run comparison --pg-inverse magic", "'magic'");
  expect_rejected("run sensitivity --no-such-option 1", "--no-such-option");
  expect_rejected("run poisson --pretrain -1",
                  "--pretrain: '-1' is neither auto nor a whole number from 0 to 10⁹");
  expect_rejected("run poisson --pretrain soon", "--pretrain: 'soon'");
  expect_rejected("run oscillators --pretrain 2.5", "--pretrain: '2.5'");
}

TEST_F(Cli, UnwritableOutputFolderIsRejected) {
  {
    std::ofstream file(dir_ / "a-file");
  }
  for (const std::string out : {"a-file/sub", "/proc/physgrad-run"}) {
    const Outcome outcome = run("run scaled-toy --iters 5 --out " + out);
    EXPECT_EQ(outcome.exit_code, 2) << out;
    EXPECT_EQ(std::count(outcome.err.begin(), outcome.err.end(), '\n'), 1) << outcome.err;
    EXPECT_NE(outcome.err.find(out.substr(0, out.find('/', 1))), std::string::npos)
        << outcome.err;
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
  // A non-empty folder is never overwritten.
  fs::create_directories(dir_ / "full");
  { std::ofstream keep(dir_ / "full" / "keep.txt"); }
  const Outcome outcome = run("run scaled-toy --iters 5 --out full");
  EXPECT_EQ(outcome.exit_code, 2);
  EXPECT_NE(outcome.err.find("not empty"), std::string::npos) << outcome.err;
  EXPECT_TRUE(fs::exists(dir_ / "full" / "keep.txt"));
}

TEST_F(Cli, HelpListsEveryOptionWithItsDefault) {
  const Outcome top = run("--help");
  EXPECT_EQ(top.exit_code, 0);
  EXPECT_NE(top.out.find("run"), std::string::npos);
  const Outcome help = run("run scaled-toy --help");
  EXPECT_EQ(help.exit_code, 0);
  for (const std::string option : {"--optimizers", "--iters", "--lr", "--seed", "--out",
                                   "--alpha", "--start", "--tol", "--tol-mode"}) {
    EXPECT_NE(help.out.find(option), std::string::npos) << option;
  }
  EXPECT_NE(help.out.find("1,10,100,1000"), std::string::npos) << help.out;
  const Outcome list = run("list");
  EXPECT_EQ(list.exit_code, 0);
  for (const std::string name : {"scaled-toy", "sensitivity", "comparison"}) {
    EXPECT_NE(list.out.find(name), std::string::npos) << name;
  }
}

TEST_F(Cli, RunWritesTheWholeRunFolder) {
  const Outcome outcome = run("run comparison --out result");
  ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
  const fs::path result = dir_ / "result";
  for (const std::string file : {"config.json", "metrics.csv", "summary.json", "report.html",
                                 "trajectories_x.svg", "trajectories_y.svg", "loss.svg"}) {
    EXPECT_TRUE(fs::exists(result / file)) << file;
  }
  const auto summary = nlohmann::json::parse(read_file(result / "summary.json"));
  EXPECT_EQ(summary["experiment"], "comparison");
  // gd, adam, newton, ig and PG with two inverses.
  ASSERT_EQ(summary["runs"].size(), 6u);
  for (const auto& entry : summary["runs"]) {
    for (const char* key : {"label", "optimizer", "params", "initial", "final", "iterations",
                            "wall_seconds"}) {
      EXPECT_TRUE(entry.contains(key)) << key;
    }
    EXPECT_LT(entry["final"]["loss"].get<double>(), entry["initial"]["loss"].get<double>())
        << entry["label"];
  }
  const auto config = nlohmann::json::parse(read_file(result / "config.json"));
  EXPECT_EQ(config["settings"]["iters"], 10);
  // Nothing staged or temporary stays behind, in the folder or beside it.
  EXPECT_TRUE(physgrad::testing::is_finished(result));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(Cli, BadConfigFileIsOneLineExitTwoAndWritesNothing) {
  // {file content, text the error line must contain}
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"learning-rate": 0.1})", "unknown option 'learning-rate' (known: optimizers, "},
      {R"({"lr": true})", "--lr: expected a number, got true"},
      {R"({"iters": 0})", "--iters: must be in [1, 1000000000], got '0'"},
      {R"({"iters": 2.5})", "--iters: '2.5' is not a whole number"},
      {R"({"lr": "nan"})", "--lr: 'nan' is not a number"},
      {R"({"lr": 1e999})", "invalid JSON at line 1, column 12: number overflow"},
      {R"({"optimizers": []})", "--optimizers: needs at least one value"},
      {R"({"optimizers": ["gd", "gd"]})", "--optimizers: 'gd' is listed twice"},
      {R"({"pg-inverse": ["magic"]})", "--pg-inverse: unknown value 'magic'"},
      {R"({"experiment": "scaled-toy", "command": "", "settings": {}})",
       "saved for experiment 'scaled-toy', not 'comparison'"},
      {"{\"lr\": 0.1,\n", "invalid JSON at line 2, column 0: "},
      {"[1, 2]", "expected a JSON object of option values, got [1,2]"},
      {R"({"lr": "1\n2"})", "--lr: '1\\x0a2' is not a number"},  // one line even so
      {R"({"iters": "5 "})", "--iters: '5 ' is not a whole number"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const std::string path = write_config("bad" + std::to_string(i) + ".json", cases[i].first);
    expect_rejected("run comparison --config " + path, "config file '" + path + "': ");
    expect_rejected("run comparison --config " + path, cases[i].second);
  }
  expect_rejected("run comparison --config missing.json",
                  "config file 'missing.json': cannot open: No such file or directory");
  expect_rejected("run comparison --config " + configs_.string(), "is a directory");
  expect_rejected("run oscillators --config missing.json", "config file 'missing.json'");
}

TEST_F(Cli, FlagsOverrideTheConfigFile) {
  const std::string config =
      write_config("c.json", R"({"iters": 3, "lr": 0.05, "pg-inverse": ["ig"], "threads": null})");
  const Outcome outcome = run("run comparison --config " + config + " --iters 2 --out result");
  ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
  const auto settings = nlohmann::json::parse(read_file(dir_ / "result" / "config.json"))["settings"];
  EXPECT_EQ(settings["iters"], 2);
  EXPECT_EQ(settings["lr"], 0.05);
  EXPECT_EQ(settings["pg-inverse"], nlohmann::json::array({"ig"}));
  EXPECT_TRUE(settings["threads"].is_null());
  const auto summary = nlohmann::json::parse(read_file(dir_ / "result" / "summary.json"));
  for (const auto& entry : summary["runs"]) EXPECT_EQ(entry["iterations"], 2) << entry["label"];
}

TEST_F(Cli, SavedConfigReproducesTheRun) {
  ASSERT_EQ(run("run comparison --iters 7 --start 2,-1.5 --lr 0.03 --out first").exit_code, 0);
  const Outcome again = run("run comparison --config first/config.json --out second");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  auto first_config = nlohmann::json::parse(read_file(dir_ / "first" / "config.json"));
  auto second_config = nlohmann::json::parse(read_file(dir_ / "second" / "config.json"));
  EXPECT_EQ(second_config["settings"]["out"], "second");
  first_config["settings"].erase("out");
  second_config["settings"].erase("out");
  EXPECT_EQ(second_config["settings"], first_config["settings"]);

  const auto first = nlohmann::json::parse(read_file(dir_ / "first" / "summary.json"))["runs"];
  const auto second = nlohmann::json::parse(read_file(dir_ / "second" / "summary.json"))["runs"];
  ASSERT_EQ(first.size(), 6u);
  ASSERT_EQ(second.size(), first.size());
  for (std::size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(second[i]["label"], first[i]["label"]);
    EXPECT_EQ(second[i]["iterations"], 7);
    EXPECT_EQ(second[i]["final"]["loss"].get<double>(), first[i]["final"]["loss"].get<double>())
        << first[i]["label"];
    EXPECT_EQ(second[i]["final"]["x"], first[i]["final"]["x"]) << first[i]["label"];
  }
  // The saved folder is a setting too: rerunning into it is refused, and nothing is touched.
  const Outcome into_first = run("run comparison --config first/config.json");
  EXPECT_EQ(into_first.exit_code, 2);
  EXPECT_NE(into_first.err.find("'first' holds the results of a finished run"), std::string::npos)
      << into_first.err;
}

TEST_F(Cli, DescribeShowsEveryOptionAndRejectsUnknownExperiments) {
  const Outcome outcome = run("describe scaled-toy");
  ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
  EXPECT_NE(outcome.out.find("scaled-toy — P(x) = (x1, alpha*x2)"), std::string::npos)
      << outcome.out;
  // One line per option: name, kind, default, range, help.
  const auto line_of = [&](const std::string& name) {
    std::istringstream lines(outcome.out);
    for (std::string line; std::getline(lines, line);) {
      if (line.starts_with(name + "  ")) return line;
    }
    return std::string();
  };
  const std::vector<std::vector<std::string>> expected = {
      {"lr", "real", "unset", "> 0", "step size"},
      {"iters", "integer", "1000", "in [1, 1000000000]", "iterations per run"},
      {"alpha", "real list", "1,10,100,1000", "> 0", "scales α"},
      {"tol-mode", "text", "relative", "one of: relative, absolute", "relative: stop"},
      {"out", "text", "unset", "any", "run folder"},
      {"optimizers", "text list", "gd,momentum,", "one of: gd, momentum,", "comma-separated"}};
  for (const auto& fields : expected) {
    const std::string line = line_of(fields[0]);
    std::size_t at = 0;
    for (const std::string& field : fields) {
      at = line.find(field, at);
      ASSERT_NE(at, std::string::npos) << field << " in: " << line << "\n" << outcome.out;
    }
  }
  const Outcome unknown = run("describe no-such-experiment");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_EQ(unknown.err, run("run no-such-experiment").err);
  EXPECT_EQ(std::count(unknown.err.begin(), unknown.err.end(), '\n'), 1) << unknown.err;
  EXPECT_NE(unknown.err.find("unknown experiment 'no-such-experiment'"), std::string::npos);
  const Outcome help = run("run scaled-toy --help");
  EXPECT_NE(help.out.find("--config FILE.json"), std::string::npos) << help.out;
}

// Each evaluation of a hig run records what the last step's inversion did; adam's rows and the
// untrained network's row leave those cells empty.
TEST_F(Cli, LearningMetricsRecordTheInversionOfEachEvaluation) {
  const Outcome outcome =
      run("run hig-toy --seeds 1 --iters 20 --eval-every 10 --optimizers adam,hig --out m");
  ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
  const physgrad::CsvData metrics = physgrad::parse_csv(read_file(dir_ / "m" / "metrics.csv"));
  const std::size_t optimizer = metrics.column("optimizer"), iteration = metrics.column("iteration");
  std::vector<std::size_t> step_columns;
  for (const char* name :
       {"pinv_path", "pinv_precision", "pinv_eigensolver", "kept_directions", "kept_condition"}) {
    step_columns.push_back(metrics.column(name));
    ASSERT_LT(step_columns.back(), metrics.columns.size()) << name;
  }
  int hig_rows = 0, hig_runs = 0;
  for (const auto& row : metrics.rows) {
    hig_runs += row[optimizer] == "hig" && row[iteration] == "0";
    const bool stepped = row[optimizer] == "hig" && row[iteration] != "0";
    for (const std::size_t c : step_columns) {
      EXPECT_EQ(row[c].empty(), !stepped) << metrics.columns[c] << " of " << row[optimizer];
    }
    if (!stepped) continue;
    ++hig_rows;
    EXPECT_EQ(row[step_columns[0]], "normal");  // 256 rows > 30 columns
    EXPECT_EQ(row[step_columns[1]], "double");
    EXPECT_TRUE(row[step_columns[2]] == "tridiagonal" || row[step_columns[2]] == "subset");
    EXPECT_GT(std::stod(row[step_columns[3]]), 0.0);
    EXPECT_GE(std::stod(row[step_columns[4]]), 1.0);
  }
  EXPECT_GT(hig_runs, 0);
  EXPECT_EQ(hig_rows, 2 * hig_runs);  // the evaluations after iterations 10 and 20
}

// --precision and --eigensolver reach gn and hig (their choices come from the rules' description)
// and the metrics say what ran; another value is a one-line error naming it.
TEST_F(Cli, PrecisionAndEigensolverOptionsReachTheInversion) {
  const Outcome outcome = run(
      "run hig-toy --seeds 1 --lambda 1 --iters 10 --eval-every 10 --optimizers hig "
      "--precision float --eigensolver full --out f");
  ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
  const physgrad::CsvData metrics = physgrad::parse_csv(read_file(dir_ / "f" / "metrics.csv"));
  const std::size_t iteration = metrics.column("iteration"),
                    precision = metrics.column("pinv_precision"),
                    eigensolver = metrics.column("pinv_eigensolver");
  ASSERT_LT(precision, metrics.columns.size());
  int stepped = 0;
  for (const auto& row : metrics.rows) {
    if (row[iteration] == "0") continue;
    ++stepped;
    EXPECT_EQ(row[precision], "float");
    EXPECT_EQ(row[eigensolver], "full");
  }
  EXPECT_EQ(stepped, 1);
  const Outcome bad = run("run hig-toy --precision quad --iters 5");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(bad.err,
            "physgrad: error: --precision: unknown value 'quad' (known: double, float, auto)\n");
}

// bench: one JSON line with the step time, its split, the shape of J, the backend and the
// reference eigendecomposition of a B·m × B·m matrix; bad names and numbers are one-line errors.
TEST_F(Cli, BenchPrintsOneJsonLineAndRejectsBadInput) {
  const Outcome outcome = run("bench hig-toy --optimizer gn --steps 2 --warmup 1");
  ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
  ASSERT_EQ(std::count(outcome.out.begin(), outcome.out.end(), '\n'), 1) << outcome.out;
  const nlohmann::json line = nlohmann::json::parse(outcome.out);
  EXPECT_EQ(line["experiment"], "hig-toy");
  EXPECT_EQ(line["optimizer"], "gn");
  EXPECT_EQ(line["batch"], 128);  // the rule's default in hig-toy
  EXPECT_EQ(line["steps"], 2);
  EXPECT_EQ(line["warmup"], 1);
  EXPECT_EQ(line["jacobian_shape"], nlohmann::json({256, 30}));  // B·m × |θ| of the 1-7-2 net
  EXPECT_EQ(line["backend"], "normal");                           // 256 rows > 30 columns
  EXPECT_GT(line["seconds_per_step"].get<double>(), 0.0);
  for (const char* part : {"jacobian", "inverse", "update", "other"}) {
    EXPECT_GE(line["split"][part].get<double>(), 0.0) << part;
  }
  EXPECT_EQ(line["reference_linalg"]["operation"], "dsyevd");
  EXPECT_EQ(line["reference_linalg"]["n"], 256);
  EXPECT_GT(line["reference_linalg"]["seconds"].get<double>(), 0.0);

  const Outcome sip = run("bench poisson --optimizer sip --batch 4 --steps 1 --warmup 0");
  ASSERT_EQ(sip.exit_code, 0) << sip.err;
  const nlohmann::json sip_line = nlohmann::json::parse(sip.out);
  EXPECT_EQ(sip_line["jacobian_shape"], nlohmann::json({256, 24896}));
  EXPECT_EQ(sip_line["backend"], "local inverse");

  for (const auto& [args, needle] : std::vector<std::pair<std::string, std::string>>{
           {"bench no-such-case", "unknown reference configuration 'no-such-case'"},
           {"bench hig-toy --optimizer newton", "unknown learning update 'newton'"},
           {"bench hig-toy --steps 0", "--steps: must be in [1, 1000000]"},
           {"bench hig-toy --batch x", "--batch: 'x' is not a whole number"},
           {"bench hig-toy --threads 0", "--threads: "}}) {
    const Outcome bad = run(args);
    EXPECT_EQ(bad.exit_code, 2) << args;
    EXPECT_TRUE(bad.out.empty()) << args << ": " << bad.out;
    EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << args << ": " << bad.err;
    EXPECT_NE(bad.err.find(needle), std::string::npos) << args << ": " << bad.err;
  }
}

}  // namespace
