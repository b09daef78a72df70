// Every registered experiment runs to the end with its defaults through the command line, the
// checkpoints its learning runs write included; only the sizes and limits that declare a quick
// value (OptionSpec::quick: samples, seeds, iterations, time steps) are made tiny. An experiment
// added to the registry is covered without touching this file.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "cli_fixture.hpp"
#include "registry.hpp"
#include "physgrad/run/life/experiment.hpp"

namespace {

using physgrad::testing::Cli;
using physgrad::testing::Outcome;
using physgrad::testing::read_file;
namespace ex = physgrad::run;
using physgrad::experiments::builtin_registry;
namespace fs = std::filesystem;

class Defaults : public Cli, public ::testing::WithParamInterface<std::string> {};

TEST_P(Defaults, RunToTheEndWithACompleteResult) {
  const ex::Experiment& experiment = builtin_registry().find(GetParam());
  std::string args = "run " + experiment.name() + " --out result";
  for (const ex::OptionSpec& spec : ex::all_options(experiment)) {
    if (!spec.quick_text.empty()) args += " --" + spec.name + " " + spec.quick_text;
  }
  const Outcome outcome = run(args);
  ASSERT_EQ(outcome.exit_code, 0) << args << "\n" << outcome.err;

  const fs::path folder = dir_ / "result";
  for (const char* file : {"config.json", "metrics.csv", "summary.json", "report.html"}) {
    EXPECT_TRUE(fs::is_regular_file(folder / file)) << file;
  }
  EXPECT_FALSE(fs::exists(folder / "checkpoint.pgc"));
  // Every selected rule ran and ended in a way other than a stop request, with finite losses.
  const nlohmann::json summary = nlohmann::json::parse(read_file(folder / "summary.json"));
  EXPECT_EQ(summary["experiment"], experiment.name());
  ASSERT_FALSE(summary["runs"].empty());
  std::set<std::string> ran;
  for (const nlohmann::json& entry : summary["runs"]) {
    const std::string label = entry.value("label", "");
    ran.insert(entry.value("optimizer", ""));
    EXPECT_NE(entry.value("termination", "interrupted"), "interrupted") << label;
    ASSERT_TRUE(entry["final"]["loss"].is_number()) << label << ": " << entry["final"];
    EXPECT_TRUE(std::isfinite(entry["final"]["loss"].get<double>())) << label;
  }
  for (const std::string& id : experiment.default_optimizers()) {
    EXPECT_EQ(ran.count(id), 1u) << id << " did not run";
  }
  // One metrics row or more per run, and no value that is not a number.
  const std::string metrics = read_file(folder / "metrics.csv");
  EXPECT_GT(std::count(metrics.begin(), metrics.end(), '\n'), static_cast<long>(summary["runs"].size()));
  EXPECT_EQ(metrics.find("nan"), std::string::npos);
  // config.json holds the settings the run used, quick values included.
  const nlohmann::json settings =
      nlohmann::json::parse(read_file(folder / "config.json"))["settings"];
  for (const ex::OptionSpec& spec : ex::all_options(experiment)) {
    if (spec.quick_text.empty()) continue;
    EXPECT_EQ(settings[spec.name], ex::parse_option(spec, spec.quick_text)) << spec.name;
  }
}

std::vector<std::string> registered() {
  std::vector<std::string> names;
  for (const auto& experiment : builtin_registry()) names.push_back(experiment->name());
  return names;
}

INSTANTIATE_TEST_SUITE_P(Experiment, Defaults, ::testing::ValuesIn(registered()),
                         [](const ::testing::TestParamInfo<std::string>& param) {
                           std::string name = param.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

}  // namespace
