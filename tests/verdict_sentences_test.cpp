// Message sentences checked against the runs they speak of: in comparison, every rule that ends
// level with the closest (within a relative 1e-4) is named with it, none ranked above the others.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_fixture.hpp"

namespace {

using physgrad::testing::Cli;
using physgrad::testing::read_file;

TEST_F(Cli, ComparisonNamesEveryRuleLevelWithTheClosest) {
  ASSERT_EQ(run("run comparison --out result").exit_code, 0);
  const nlohmann::json summary = nlohmann::json::parse(read_file(dir_ / "result/summary.json"));
  const std::string sentence = summary.at("message").at("sentence");
  double smallest = INFINITY;
  for (const nlohmann::json& r : summary.at("runs")) {
    smallest = std::min(smallest, r.at("final").at("x_distance").get<double>());
  }
  // The names before "end(s) … from the minimum", each after "steps " or " and ".
  const std::string head = sentence.substr(0, sentence.find(" from the minimum"));
  const auto named = [&](const std::string& label) {
    const std::vector<std::string> befores = {"steps ", " and "}, afters = {" and ", " end"};
    for (const std::string& before : befores) {
      for (const std::string& after : afters) {
        if (head.find(before + label + after) != std::string::npos) return true;
      }
    }
    return false;
  };
  std::size_t level = 0;
  for (const nlohmann::json& r : summary.at("runs")) {
    const std::string label = r.at("label");
    const bool is_level = r.at("final").at("x_distance").get<double>() <= smallest * (1 + 1e-4);
    level += is_level;
    EXPECT_EQ(named(label), is_level) << label << ": " << sentence;
  }
  ASSERT_GE(level, 2u) << "the default run has rules level with the closest: " << sentence;
  EXPECT_NE(sentence.find("(level within a relative 1e-4)"), std::string::npos) << sentence;
}

}  // namespace
