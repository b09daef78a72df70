// Run::start and Run::resume as a front end other than the CLI calls them: the run folder they
// leave, what they hand back, their errors, and a run stopped on request and resumed in the same
// process to the results of an uninterrupted one.
#include "physgrad/run/run.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli_fixture.hpp"
#include "physgrad/error.hpp"
#include "physgrad/run/life/config_file.hpp"
#include "registry.hpp"
#include "physgrad/stop.hpp"

namespace {

namespace fs = std::filesystem;
namespace ex = physgrad::run;
using physgrad::experiments::builtin_registry;
using physgrad::testing::is_finished;
using physgrad::testing::metrics_without_time;
using physgrad::testing::read_file;

class RunCall : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("physgrad_run_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    physgrad::clear_stop_request();
    fs::remove_all(dir_);
  }

  static ex::Settings settings(const std::string& name, const ex::OptionTexts& given) {
    return ex::resolve_settings(builtin_registry().find(name), given);
  }

  fs::path dir_;
};

// A learning run small enough for a test: one seed of each of three rules, checkpoints often.
const ex::OptionTexts kLearning = {{"seeds", "1"},       {"lambda", "0.01"},
                                   {"iters", "300"},     {"eval-every", "50"},
                                   {"train-size", "64"}, {"test-size", "16"},
                                   {"checkpoint-every", "25"}};

TEST_F(RunCall, StartWritesTheFolderAndReturnsItsSummary) {
  const ex::Experiment& experiment = builtin_registry().find("comparison");
  std::vector<std::string> progress, notices;
  ex::RunHooks hooks;
  hooks.progress = [&](const std::string& line) { progress.push_back(line); };
  hooks.log = [&](const std::string& text) { notices.push_back(text); };
  hooks.command = "front end call";
  const ex::RunOutcome outcome =
      ex::Run::start(experiment, settings("comparison", {{"iters", "5"}}), dir_ / "a", hooks);
  ASSERT_TRUE(outcome.finished);
  EXPECT_EQ(outcome.folder, dir_ / "a");
  EXPECT_EQ(outcome.report, dir_ / "a" / "report.html");
  EXPECT_TRUE(is_finished(dir_ / "a"));
  ASSERT_TRUE(outcome.summary.has_value());
  const nlohmann::json written = nlohmann::json::parse(read_file(dir_ / "a" / "summary.json"));
  EXPECT_EQ(written, ex::run_summary_json(*outcome.summary));
  EXPECT_EQ(ex::run_summary_json(ex::read_run_summary(written)), written);
  EXPECT_EQ(outcome.summary->experiment, "comparison");
  ASSERT_FALSE(outcome.summary->runs.empty());
  for (const auto& run : outcome.summary->runs) EXPECT_FALSE(run.termination.empty());
  EXPECT_FALSE(outcome.tables.empty());
  EXPECT_FALSE(progress.empty());
  EXPECT_TRUE(notices.empty());
  EXPECT_EQ(nlohmann::json::parse(read_file(dir_ / "a" / "config.json"))["command"],
            "front end call");

  // A finished folder is never written again; the error names it.
  const auto before = physgrad::testing::snapshot(dir_ / "a");
  try {
    ex::Run::start(experiment, settings("comparison", {{"iters", "5"}}), dir_ / "a");
    FAIL() << "no error";
  } catch (const physgrad::Error& e) {
    EXPECT_NE(std::string(e.what()).find((dir_ / "a").string()), std::string::npos) << e.what();
  }
  EXPECT_EQ(physgrad::testing::snapshot(dir_ / "a"), before);
  EXPECT_THROW(ex::Run::resume(builtin_registry(), dir_ / "a"), physgrad::Error);
}

TEST_F(RunCall, TheOutFolderComesFromTheCallThenTheSettings) {
  const ex::Experiment& experiment = builtin_registry().find("comparison");
  const fs::path from_settings = dir_ / "from-settings";
  const ex::RunOutcome outcome = ex::Run::start(
      experiment, settings("comparison", {{"iters", "2"}, {"out", from_settings.string()}}), {});
  EXPECT_EQ(outcome.folder, from_settings);
  EXPECT_TRUE(is_finished(from_settings));
  // A blank --out is refused, not taken for the default folder.
  try {
    ex::Run::start(experiment, settings("comparison", {{"iters", "2"}, {"out", " "}}), {});
    FAIL() << "no error";
  } catch (const physgrad::Error& e) {
    EXPECT_EQ(std::string(e.what()), "--out: '' is blank; name a folder");
  }
}

TEST_F(RunCall, AStoppedRunResumesToTheResultsOfAnUninterruptedOne) {
  const ex::Experiment& experiment = builtin_registry().find("hig-toy");
  const ex::RunOutcome whole =
      ex::Run::start(experiment, settings("hig-toy", kLearning), dir_ / "whole");
  ASSERT_TRUE(whole.finished);

  // Stop at the eighth progress line (the second rule's run is in progress).
  int lines = 0;
  ex::RunHooks hooks;
  hooks.progress = [&](const std::string&) {
    if (++lines == 8) physgrad::request_stop();
  };
  const ex::RunOutcome stopped =
      ex::Run::start(experiment, settings("hig-toy", kLearning), dir_ / "part", hooks);
  EXPECT_FALSE(stopped.finished);
  EXPECT_EQ(stopped.signal, 0);
  EXPECT_NE(stopped.stopped.find("checkpoint kept, continue with: physgrad resume"),
            std::string::npos)
      << stopped.stopped;
  EXPECT_FALSE(stopped.summary.has_value());
  EXPECT_TRUE(fs::exists(dir_ / "part" / "checkpoint.pgc"));
  EXPECT_FALSE(fs::exists(dir_ / "part" / "summary.json"));

  physgrad::clear_stop_request();
  const ex::RunOutcome resumed = ex::Run::resume(builtin_registry(), dir_ / "part");
  ASSERT_TRUE(resumed.finished);
  EXPECT_TRUE(is_finished(dir_ / "part"));
  EXPECT_EQ(metrics_without_time(dir_ / "part"), metrics_without_time(dir_ / "whole"));
  EXPECT_EQ(read_file(dir_ / "part" / "networks.json"), read_file(dir_ / "whole" / "networks.json"));
  ASSERT_TRUE(resumed.summary && whole.summary);
  ASSERT_EQ(resumed.summary->runs.size(), whole.summary->runs.size());
  for (std::size_t i = 0; i < whole.summary->runs.size(); ++i) {
    EXPECT_EQ(ex::run_entry_json(resumed.summary->runs[i])["final"],
              ex::run_entry_json(whole.summary->runs[i])["final"])
        << i;
  }
}

TEST_F(RunCall, ResumeNamesWhatIsWrongWithTheFolder) {
  const auto message = [](const fs::path& dir) -> std::string {
    try {
      ex::Run::resume(builtin_registry(), dir);
    } catch (const physgrad::Error& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_NE(message(dir_ / "absent").find("absent"), std::string::npos);
  fs::create_directories(dir_ / "other");
  std::ofstream(dir_ / "other" / "config.json") << R"({"experiment": "no-such", "settings": {}})";
  EXPECT_NE(message(dir_ / "other").find("unknown experiment 'no-such'"), std::string::npos)
      << message(dir_ / "other");
}

}  // namespace
