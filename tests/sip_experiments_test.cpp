// The SIP learning experiments sin-rotation, heat-inverse and sip-poisson through the experiment API: short
// runs limited by iterations (not time, so they are deterministic) that must show the outcome
// each experiment exists for.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "registry.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "experiment_runs.hpp"
#include "physgrad/error.hpp"

namespace physgrad::run {
namespace {

using testing::run_experiment;

// The first and last metrics rows of one rule.
std::pair<nlohmann::json, nlohmann::json> first_and_last(const RunContext& context,
                                                         const std::string& optimizer) {
  std::vector<nlohmann::json> rows;
  for (const nlohmann::json& row : context.metrics()) {
    if (row["optimizer"] == optimizer) rows.push_back(row);
  }
  if (rows.empty()) throw Error("no metrics for " + optimizer);
  return {rows.front(), rows.back()};
}

// docs/reference_experiments.md (sin-rotation), shortened: at ξ = 32 SIP ends far nearer the
// exact solutions.
TEST(SinRotationExperiment, SipEndsNearerTheExactSolutionsThanAdamWhenIllConditioned) {
  const RunContext context = run_experiment("sin-rotation", {{"xi", "32"},
                                                  {"optimizers", "sip,adam"},
                                                  {"iters", "300"},
                                                  {"time", "1e6"},
                                                  {"eval-every", "100"},
                                                  {"train-size", "2000"},
                                                  {"test-size", "200"}});
  const auto [sip_start, sip_end] = first_and_last(context, "sip");
  const auto [adam_start, adam_end] = first_and_last(context, "adam");
  EXPECT_EQ(sip_end["iteration"], 300);
  EXPECT_EQ(adam_end["iteration"], 300);
  const double sip = sip_end["x_distance"], adam = adam_end["x_distance"];
  EXPECT_LT(sip, 0.25 * adam);
  EXPECT_LT(sip, sip_start["x_distance"].get<double>());
  EXPECT_LT(adam, adam_start["x_distance"].get<double>());
  // Figures for ξ = 32: loss vs iteration and time, x-distance; the landscape at ξ = 1.
  EXPECT_EQ(context.figures().size(), 4u);
}

// docs/reference_experiments.md (heat-inverse), shortened: after the same iterations SIP
// reconstructs x* better.
TEST(HeatExperiment, SipReconstructsTheInitialStateBetterThanAdam) {
  const RunContext context = run_experiment("heat-inverse", {{"network", "mlp"},
                                                  {"dims", "1"},
                                                  {"data", "fixed"},
                                                  {"iters", "300"},
                                                  {"eval-every", "100"},
                                                  {"train-size", "512"},
                                                  {"test-size", "64"}});
  for (const std::string id : {"sip", "adam"}) {
    const auto [start, end] = first_and_last(context, id);
    EXPECT_EQ(end["iteration"], 300) << id;
    EXPECT_LT(end["test_loss"].get<double>(), start["test_loss"].get<double>()) << id;
    EXPECT_LT(end["x_loss"].get<double>(), start["x_loss"].get<double>()) << id;
  }
  const double sip = first_and_last(context, "sip").second["x_loss"];
  const double adam = first_and_last(context, "adam").second["x_loss"];
  EXPECT_LT(sip, 0.9 * adam);
}

// The U-net experiments shrunk to 16×16 cells and 4 filters, 20 updates on fresh batches of 8.
const std::vector<std::pair<std::string, std::string>> kSmallUNet = {
    {"n", "16"},         {"filters", "4"},  {"iters", "20"}, {"eval-every", "10"},
    {"train-size", "16"}, {"test-size", "8"}, {"batch", "8"}};

// The default heat-inverse on a small U-net: both rules lower the reconstruction error, and the
// report carries the table beside the published values.
TEST(HeatExperiment, UNetRunsLowerTheReconstructionErrorOfBothRules) {
  const RunContext context = run_experiment("heat-inverse", kSmallUNet);
  for (const std::string id : {"sip", "adam"}) {
    const auto [start, end] = first_and_last(context, id);
    EXPECT_EQ(end["iteration"], 20) << id;
    EXPECT_LT(end["x_loss"].get<double>(), start["x_loss"].get<double>()) << id;
    EXPECT_LT(end["x_l1"].get<double>(), start["x_l1"].get<double>()) << id;
  }
  bool reference = false;
  for (const RunContext::Table& table : context.tables()) {
    reference |= table.title.starts_with("Published values");
  }
  EXPECT_TRUE(reference);
}

// sip-poisson on a small U-net: both rules bring x nearer x* (Σ|x − x*|).
TEST(SipPoissonExperiment, BothRulesBringTheSolutionNearerTheTruth) {
  const RunContext context = run_experiment("sip-poisson", kSmallUNet);
  for (const std::string id : {"sip", "adam"}) {
    const auto [start, end] = first_and_last(context, id);
    EXPECT_EQ(end["iteration"], 20) << id;
    EXPECT_LT(end["x_l1"].get<double>(), start["x_l1"].get<double>()) << id;
  }
}

TEST(HeatExperiment, RejectsTwoDimensionalGridsTooLargeForTheNetwork) {
  const Experiment& experiment = experiments::builtin_registry().find("heat-inverse");
  try {
    resolve_settings(experiment, {{"network", "mlp"}, {"dims", "2"}, {"n", "40"}});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("got 40"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace physgrad::run
