// The interactive comparison's data block and policy: escaping that no value can close the
// block, the script's hash (FIPS 180-4 vectors), the data read from a metrics.csv, and what a
// report page says when it leaves the comparison out.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/report/compare_view.hpp"
#include "physgrad/run/life/run_machine.hpp"
#include "physgrad/run/pages/report_page.hpp"
#include "physgrad/run/pages/run_compare_data.hpp"
#include "registry.hpp"

namespace {

TEST(CompareView, JsonForScriptEscapesWhatCouldCloseTheBlockAndStaysTheSameJson) {
  const std::string hostile =
      "</script><script>alert(1)</script> <!-- \"><img src=x onerror=alert(1)> & "
      "\xe2\x80\xa8\xe2\x80\xa9 é";
  const std::string text = nlohmann::json{{"l", hostile}}.dump();
  const std::string escaped = physgrad::json_for_script(text);
  for (const char* banned : {"<", ">", "&", "=", "\xe2\x80\xa8", "\xe2\x80\xa9"}) {
    EXPECT_EQ(escaped.find(banned), std::string::npos) << banned << " in " << escaped;
  }
  EXPECT_NE(escaped.find("\\u003c/script\\u003e"), std::string::npos) << escaped;
  EXPECT_NE(escaped.find("\\u2028\\u2029"), std::string::npos) << escaped;
  EXPECT_NE(escaped.find("é"), std::string::npos) << "other characters are kept: " << escaped;
  EXPECT_EQ(nlohmann::json::parse(escaped).at("l").get<std::string>(), hostile);
}

TEST(CompareView, Sha256Base64MatchesTheStandardsVectors) {
  // FIPS 180-4 examples: "abc", the empty text, and a two-block message.
  EXPECT_EQ(physgrad::sha256_base64("abc"), "ungWv48Bz+pBQUDeXa4iI7ADYaOWF3qctBD/YfIAFa0=");
  EXPECT_EQ(physgrad::sha256_base64(""), "47DEQpj8HBSa+/TImW+5JCeuQeRkm5NMpJWZG3hSuFU=");
  EXPECT_EQ(physgrad::sha256_base64("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "JI1qYdIGOLjlwCaTDD5gOaM85Flk/yFn9uzt1BnbBsE=");
}

TEST(CompareView, PolicyAllowsExactlyTheScriptAndNoRequest) {
  const std::string csp = physgrad::compare_csp();
  EXPECT_NE(csp.find("default-src 'none'"), std::string::npos);
  EXPECT_NE(csp.find("script-src 'sha256-" + physgrad::sha256_base64(physgrad::kCompareScript) +
                     "'"),
            std::string::npos)
      << csp;
  EXPECT_EQ(csp.find("connect-src"), std::string::npos);
  EXPECT_EQ(csp.find("unsafe-eval"), std::string::npos);
  EXPECT_EQ(physgrad::kCompareScript.find("innerHTML"), std::string::npos);
  const std::string close = physgrad::compare_section_close();
  EXPECT_NE(close.find("<script>" + std::string(physgrad::kCompareScript) + "</script>"),
            std::string::npos);
}

TEST(CompareData, RunsPerLabelSeedAndRestartWithNumericColumnsThinned) {
  std::string csv = "label,seed,iteration,wall_seconds,test_loss,optimizer\n";
  for (int i = 0; i < 5000; ++i) {
    csv += "</script>,0," + std::to_string(i) + "," + std::to_string(i * 0.5) + ",1,adam\n";
  }
  csv += "b,1,0,0,nan,gd\nb,1,1,1,2,gd\nb,1,0,0,3,gd\n";  // b restarts: a second setting
  std::vector<std::string> notes;
  const std::string runs = physgrad::run::compare_runs_json("folder", csv, notes);
  EXPECT_EQ(runs.find('<'), std::string::npos);
  const nlohmann::json parsed = nlohmann::json::parse("[" + runs + "]");
  ASSERT_EQ(parsed.size(), 3u) << runs.substr(0, 300);
  EXPECT_EQ(parsed[0].at("l"), "</script>");
  EXPECT_EQ(parsed[0].at("g"), "folder");
  const auto& first = parsed[0].at("c");
  EXPECT_FALSE(first.contains("optimizer"));
  EXPECT_FALSE(first.contains("seed"));
  EXPECT_LE(first.at("iteration").size(), physgrad::run::kCompareMaxPoints);
  EXPECT_GE(first.at("iteration").size(), physgrad::run::kCompareMaxPoints / 2);
  EXPECT_EQ(first.at("iteration").front(), 0.0);
  EXPECT_EQ(first.at("iteration").back(), 4999.0);
  EXPECT_TRUE(parsed[1].at("c").at("test_loss").at(0).is_null());  // nan
  EXPECT_EQ(parsed[1].at("c").at("test_loss").size(), 2u);
  EXPECT_EQ(parsed[2].at("c").at("test_loss").at(0), 3.0);
  EXPECT_TRUE(notes.empty());
  EXPECT_THROW(physgrad::run::compare_runs_json("f", "a,b\n1\n", notes), physgrad::Error);
}

// A metrics.csv the comparison cannot read leaves the report without it, and the page says why.
TEST(CompareView, AReportPageSaysWhyItHasNoInteractiveComparison) {
  namespace run = physgrad::run;
  const run::Experiment& experiment = physgrad::experiments::builtin_registry().find("comparison");
  const run::Settings settings = run::resolve_settings(experiment, {});
  const run::RunContext context;
  const std::string page =
      run::report_page_html(experiment, settings, context, "", false, run::run_machine(),
                            "a,b\n1\n");
  EXPECT_NE(page.find("The interactive comparison is left out: "), std::string::npos);
  EXPECT_EQ(page.find("Interactive comparison"), std::string::npos);
}

}  // namespace
