// summary.json through its one writer and one reader (run/life/run_summary.hpp): a summary
// written and read back is the same summary, a file of an older version reads, and a field of
// the wrong type is named.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "physgrad/error.hpp"
#include "physgrad/run/life/run_summary.hpp"

namespace physgrad::run {
namespace {

RunSummary two_run_summary() {
  RunSummary summary;
  summary.experiment = "hig-toy";
  summary.machine = {{"commit", "abc1234"}, {"blas_threads", 1}};
  summary.message = RunMessage{"loss.svg", "HIG ends 10× below Adam.", "test_loss",
                               "median final test loss", {"HIG (λ=0.01)", "Adam (λ=0.01)"}};
  RunEntry learning;
  learning.label = "HIG (λ=0.01)";
  learning.optimizer = "hig";
  learning.params = {{"lr", 1.0}, {"batch", 128}, {"seed", 3}};
  learning.initial = {0.7, 0.8, nlohmann::json::object()};
  learning.final = {1.5e-3, std::nan(""), {{"act_mean", 0.25}}};  // not evaluated: null
  learning.iterations = 400;
  learning.epochs = 100.5;
  learning.wall_seconds = 2.25;
  learning.run_seconds = 2.5;
  learning.termination = "max_iterations";
  learning.message = "reached 400 iterations";
  learning.step_halvings = 2;
  learning.seconds_per_part = SecondsPerPart{0.5, 0.75, 0.25, 0.125};
  RunEntry direct;
  direct.label = "Newton";
  direct.optimizer = "newton";
  direct.initial.loss = 4.0;
  direct.final.loss = 0.0;
  direct.final.more = {{"x", {1.0, -2.0}}, {"simulator_passes", 17}};
  direct.iterations = 6;
  direct.wall_seconds = 0.01;
  direct.termination = "converged";
  summary.runs = {learning, direct};
  return summary;
}

// The document as the file holds it (NaN written as null).
nlohmann::json as_written(const RunSummary& summary) {
  return nlohmann::json::parse(run_summary_json(summary).dump(2));
}

TEST(RunSummary, WhatIsWrittenReadsBackAsTheSameSummary) {
  const RunSummary summary = two_run_summary();
  const nlohmann::json written = as_written(summary);
  const RunSummary read = read_run_summary(written);
  EXPECT_EQ(as_written(read), written);

  ASSERT_EQ(read.runs.size(), 2u);
  EXPECT_EQ(read.experiment, "hig-toy");
  ASSERT_TRUE(read.message.has_value());
  EXPECT_EQ(read.message->labels, summary.message->labels);
  EXPECT_EQ(read.machine, summary.machine);
  const RunEntry& learning = read.runs[0];
  EXPECT_EQ(learning.params, summary.runs[0].params);
  EXPECT_EQ(learning.epochs.value(), 100.5);
  EXPECT_EQ(learning.run_seconds.value(), 2.5);
  EXPECT_EQ(learning.step_halvings.value(), 2);
  ASSERT_TRUE(learning.seconds_per_part.has_value());
  EXPECT_EQ(learning.seconds_per_part->derivatives, 0.75);
  ASSERT_TRUE(learning.final.test_loss.has_value());
  EXPECT_TRUE(std::isnan(*learning.final.test_loss));  // null in the file
  EXPECT_EQ(learning.figure("act_mean"), 0.25);
  EXPECT_EQ(learning.figure("iterations"), 400);
  EXPECT_TRUE(std::isnan(learning.figure("test_loss")));

  const RunEntry& direct = read.runs[1];
  EXPECT_FALSE(direct.epochs.has_value());  // "epochs": null
  EXPECT_TRUE(written["runs"][1].contains("epochs"));
  EXPECT_FALSE(written["runs"][1]["final"].contains("test_loss"));
  EXPECT_FALSE(direct.final.test_loss.has_value());
  EXPECT_FALSE(direct.seconds_per_part.has_value());
  EXPECT_EQ(direct.figure("simulator_passes"), 17);
  EXPECT_EQ(direct.final.more["x"], nlohmann::json({1.0, -2.0}));
}

// A summary.json as the code wrote it before runs had "run_seconds" and summaries a "machine"
// and a "message", with a key this reader does not know.
constexpr const char* kOlderSummary = R"json({
  "experiment": "poisson",
  "runs": [
    {"label": "Adam (8x8)", "optimizer": "adam", "params": {"lr": 0.0003, "batch": 64, "seed": 0},
     "initial": {"loss": 1.25, "test_loss": 1.5}, "final": {"loss": 0.5, "test_loss": 0.625, "x_l1": 3.5},
     "iterations": 1000, "epochs": 31.25, "wall_seconds": 4.5, "termination": "time_budget",
     "message": "", "step_halvings": 0,
     "seconds_per_part": {"forward": 1, "derivatives": 2, "inversion": 0, "update": 0.5},
     "note": "kept"},
    {"label": "GD", "optimizer": "gd", "params": {}, "initial": {"loss": 2},
     "final": {"loss": 1, "x": [0.5]}, "iterations": 10, "epochs": null, "wall_seconds": 0.5,
     "termination": "max_iterations", "message": "10 iterations"}
  ]
})json";

TEST(RunSummary, AFileOfAnOlderVersionReads) {
  const nlohmann::json document = nlohmann::json::parse(kOlderSummary);
  const RunSummary read = read_run_summary(document);
  EXPECT_EQ(read.experiment, "poisson");
  EXPECT_FALSE(read.message.has_value());
  EXPECT_TRUE(read.machine.is_null());
  ASSERT_EQ(read.runs.size(), 2u);
  EXPECT_FALSE(read.runs[0].run_seconds.has_value());
  EXPECT_EQ(read.runs[0].figure("x_l1"), 3.5);
  EXPECT_EQ(read.runs[0].figure("test_loss"), 0.625);
  EXPECT_EQ(read.runs[0].more["note"], "kept");
  EXPECT_EQ(read.runs[1].iterations, 10);
  EXPECT_EQ(read.runs[1].initial.loss, 2);
  // Written again, it is the file it was read from.
  EXPECT_EQ(run_summary_json(read), document);
  // At most max_runs runs are read.
  EXPECT_EQ(read_run_summary(document, 1).runs.size(), 1u);
}

TEST(RunSummary, AFieldOfTheWrongTypeIsNamed) {
  const auto message = [](const std::string& text) {
    try {
      read_run_summary(nlohmann::json::parse(text));
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("read");
  };
  EXPECT_EQ(message(R"({"runs": [{"final": {"loss": "low"}}]})"),
            "runs[0].final.loss is a string, not a number");
  EXPECT_EQ(message(R"({"runs": [{}, {"iterations": 2.5}]})"),
            "runs[1].iterations is 2.5, not a whole number");
  EXPECT_EQ(message(R"({"runs": [7]})"), "runs[0] is a number, not an object");
  EXPECT_EQ(message(R"({"runs": [], "message": {"labels": [1]}})"),
            "message.labels holds a number, not text");
  EXPECT_EQ(message(R"({"experiment": "x"})"), "has no list of runs");
  // Absent and null fields take their defaults.
  EXPECT_EQ(message(R"({"runs": [{"label": null, "epochs": null}]})"), "read");
}

}  // namespace
}  // namespace physgrad::run
