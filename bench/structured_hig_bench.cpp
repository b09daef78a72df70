// Structured HIG against the exact step on the reference cases (hig-toy, oscillators, poisson at
// batch 16 and 64): the cost of a whole step of each rule as a multiple of an Adam step and of an
// exact HIG step measured in the same process, and the cosine between each approximate update
// and the exact one (same κ) at the same parameters, at initialisation and after Adam training.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "low_rank_tail.hpp"
#include "registry.hpp"
#include "physgrad/threads.hpp"
#include "physgrad/train/trainer.hpp"
#include "single_thread_main.hpp"

namespace {

using namespace physgrad;
using run::ReferenceCase;

struct CaseSpec {
  const char* experiment;
  Index batch;
  const char* label;
};

constexpr CaseSpec kCases[] = {
    {"hig-toy", 128, "hig_toy"},          // 0: J 256 × 30
    {"oscillators", 128, "oscillators"},  // 1: J 512 × 4972
    {"poisson", 16, "poisson"},           // 2: J 1024 × 24 896
    {"poisson", 64, "poisson_b64"},       // 3: J 4096 × 24 896
};

// A rule with the case's settings of its settings_source() and, where given, q or k.
struct RuleSpec {
  const char* id;
  int products;  // lanczos: q; 0: the rule's default
  int refresh;   // kfac: k; 0: the rule's default
  const char* label;
};

constexpr RuleSpec kRules[] = {
    {"adam", 0, 0, "adam"},                         // 0
    {"hig", 0, 0, "hig"},                           // 1
    {"kfac-hig", 0, 10, "kfac-hig k=10"},           // 2
    {"kfac-hig", 0, 1, "kfac-hig k=1"},             // 3
    {"kfac", 0, 10, "kfac k=10"},                   // 4
    {"lanczos-hig", 5, 0, "lanczos-hig q=5"},       // 5
    {"lanczos-hig", 10, 0, "lanczos-hig q=10"},     // 6
    {"lanczos-hig", 20, 0, "lanczos-hig q=20"},     // 7
    {"lanczos-hig", 50, 0, "lanczos-hig q=50"},     // 8
    {"lanczos-gn", 20, 0, "lanczos-gn q=20"},       // 9
};

const CaseSpec& case_spec(std::int64_t which) { return kCases[static_cast<std::size_t>(which)]; }
const RuleSpec& rule_spec(std::int64_t which) { return kRules[static_cast<std::size_t>(which)]; }

RuleSettings case_settings(const ReferenceCase& c, const std::string& id) {
  const auto* own = experiment_setting(c.defaults, id);
  return own == nullptr ? RuleSettings{} : own->settings;
}

std::unique_ptr<LearningUpdate> make_rule(const ReferenceCase& c, const RuleSpec& r) {
  RuleSettings settings = case_settings(c, r.id);
  if (r.products > 0) settings["products"] = r.products;
  if (r.refresh > 0) settings["refresh"] = r.refresh;
  return make_learning_update(r.id, settings);
}

// Mean seconds of `steps` whole train_step() calls of `update` from the case's network.
double seconds_per_step(const ReferenceCase& c, LearningUpdate& update, int steps) {
  Mlp network = c.network;
  StepState state;
  double total = 0;
  for (int s = 0; s < steps; ++s) {
    total += train_step(network, update, c.problem(), c.batch, state).total_seconds;
  }
  return total / steps;
}

// The exact HIG step's seconds on each case, measured once per process.
double hig_seconds(std::int64_t which, const ReferenceCase& c) {
  static std::map<std::int64_t, double> measured;
  const auto found = measured.find(which);
  if (found != measured.end()) return found->second;
  const auto hig = make_rule(c, rule_spec(1));
  return measured[which] = seconds_per_step(c, *hig, case_spec(which).batch > 32 ? 2 : 5);
}

// Whole steps of rule range(1) on case range(0); counters: adam_steps (its time over an Adam
// step's, the Adam steps timed just before) and vs_hig (over the exact HIG step's).
void structured_step(benchmark::State& state) {
  const CaseSpec& spec = case_spec(state.range(0));
  const RuleSpec& rule = rule_spec(state.range(1));
  const ReferenceCase c = experiments::builtin_registry().reference(spec.experiment, spec.batch);
  const double hig = hig_seconds(state.range(0), c);
  const auto adam_rule = make_rule(c, rule_spec(0));
  const double adam = seconds_per_step(c, *adam_rule, 200);
  Mlp network = c.network;
  const auto update = make_rule(c, rule);
  StepState step_state;
  double total = 0;
  double count = 0;
  for (auto _ : state) {
    const StepReport report = train_step(network, *update, c.problem(), c.batch, step_state);
    if (!report.applied()) {
      state.SkipWithError(describe_failure(report, 0).c_str());
      break;
    }
    total += report.total_seconds;
    ++count;
  }
  const double per_step = total / std::max(count, 1.0);
  state.counters["adam_steps"] = per_step / adam;
  state.counters["vs_hig"] = per_step / hig;
  state.counters["adam_ms"] = 1e3 * adam;
  state.SetLabel(std::string(spec.label) + " " + rule.label);
}

// Parameters at which the steps are compared: the case's initial network, and the network after
// kAdamSteps Adam steps over a pool of kPoolBatches batches; the first kCompared batches of the
// pool are the ones compared, the next kAveraged feed the running-average factors.
constexpr int kPoolBatches = 12, kCompared = 3, kAveraged = 7, kAdamSteps = 2000;

struct ComparisonPoint {
  Mlp network;
  std::vector<Dataset> batches;  // the pool, kPoolBatches batches of B samples
};

const ReferenceCase& pool_case(std::int64_t which) {
  static std::map<std::int64_t, ReferenceCase> cases;
  const auto found = cases.find(which);
  if (found != cases.end()) return found->second;
  const CaseSpec& spec = case_spec(which);
  const auto& registry = experiments::builtin_registry();
  ReferenceCase pool = registry.reference(spec.experiment, kPoolBatches * spec.batch);
  // The rules' settings are those of one batch of B (poisson's step grows with the batch), not
  // of the pool's kPoolBatches·B samples.
  pool.defaults = registry.reference(spec.experiment, spec.batch).defaults;
  return cases.emplace(which, std::move(pool)).first->second;
}

// point 0: the initial network; point 1: after Adam.
const ComparisonPoint& comparison_point(std::int64_t which, int point) {
  static std::map<std::pair<std::int64_t, int>, ComparisonPoint> points;
  const auto key = std::make_pair(which, point);
  const auto found = points.find(key);
  if (found != points.end()) return found->second;
  const ReferenceCase& c = pool_case(which);
  const Index b = case_spec(which).batch;
  ComparisonPoint p{c.network, {}};
  for (int k = 0; k < kPoolBatches; ++k) p.batches.push_back(c.batch.columns(k * b, b));
  if (point == 1) {
    const auto adam = make_rule(c, rule_spec(0));
    StepState state;
    for (int s = 0; s < kAdamSteps; ++s) {
      train_step(p.network, *adam, c.problem(), p.batches[static_cast<std::size_t>(s % kPoolBatches)],
                 state);
    }
  }
  return points.emplace(key, std::move(p)).first->second;
}

// The exact step of κ = ½ (hig) or 1 (gn) on compared batch `k` at a point, computed once.
const Vector& exact_step(std::int64_t which, int point, int k, const std::string& exact) {
  static std::map<std::tuple<std::int64_t, int, int, std::string>, Vector> steps;
  const auto key = std::make_tuple(which, point, k, exact);
  const auto found = steps.find(key);
  if (found != steps.end()) return found->second;
  const ReferenceCase& c = pool_case(which);
  const ComparisonPoint& p = comparison_point(which, point);
  MlpCache cache;
  const BatchState batch = evaluate_batch(p.network, c.problem(),
                                          p.batches[static_cast<std::size_t>(k)],
                                          UpdateNeed::kStackedJacobian, cache);
  return steps.emplace(key, make_learning_update(exact, case_settings(c, exact))->step(batch).delta)
      .first->second;
}

// The approximations compared: a rule (by kRules index), the running-average variant of kfac-hig,
// or low rank plus tail with rank k.
struct Variant {
  int rule;         // kRules index, or −1 for low rank plus tail
  bool averaged;    // kfac: factors averaged over kAveraged other batches first
  Index rank;       // low rank: k
  const char* label;
};

constexpr Variant kVariants[] = {
    {3, false, 0, "kfac-hig, this batch's factors"},   // 0
    {3, true, 0, "kfac-hig, factors averaged"},       // 1
    {4, false, 0, "kfac (vs gn)"},                     // 2
    {5, false, 0, "lanczos-hig q=5"},                  // 3
    {6, false, 0, "lanczos-hig q=10"},                 // 4
    {7, false, 0, "lanczos-hig q=20"},                 // 5
    {8, false, 0, "lanczos-hig q=50"},                 // 6
    {9, false, 0, "lanczos-gn q=20 (vs gn)"},          // 7
    {-1, false, 16, "low rank + tail k=16"},           // 8
    {-1, false, 64, "low rank + tail k=64"},           // 9
    {-1, false, 256, "low rank + tail k=256"},         // 10
};

// Cosines of variant range(1) to the exact step on case range(0): mean over the compared batches
// at initialisation (cos_init) and after Adam (cos_trained), the smallest of all (cos_min), and the
// batch-loss decrease of one step relative to the exact step's (drop_init, drop_trained).
void structured_cosine(benchmark::State& state) {
  const std::int64_t which = state.range(0);
  const Variant& variant = kVariants[static_cast<std::size_t>(state.range(1))];
  const ReferenceCase& c = pool_case(which);
  const std::string exact =
      variant.rule >= 0 ? settings_source(rule_spec(variant.rule).id) : std::string("hig");
  double cos_sum[2] = {0, 0}, drop_sum[2] = {0, 0}, cos_min = 1;
  Index products = 0;
  for (auto _ : state) {
    for (int point = 0; point < 2; ++point) {
      const ComparisonPoint& p = comparison_point(which, point);
      for (int k = 0; k < kCompared; ++k) {
        const Dataset& batch = p.batches[static_cast<std::size_t>(k)];
        const Vector& reference = exact_step(which, point, k, exact);
        MlpCache cache;
        const BatchState evaluated = evaluate_batch(p.network, c.problem(), batch,
                                                    UpdateNeed::kStackedJacobian, cache);
        Vector delta;
        if (variant.rule < 0) {
          const double rcond = make_learning_update("hig", case_settings(c, "hig"))
                                   ->params().at("rcond").get<double>();
          const double lr = make_learning_update("hig", case_settings(c, "hig"))->learning_rate();
          delta = bench::low_rank_tail_step(*evaluated.jacobian, evaluated.loss_gradient_y,
                                            variant.rank, 2, 0.5, rcond, lr, 17u + k, &products);
        } else {
          const auto rule = make_rule(c, rule_spec(variant.rule));
          if (variant.averaged) {  // refresh 1: every batch enters the running average
            for (int a = 0; a < kAveraged; ++a) {
              MlpCache other;
              rule->step(evaluate_batch(p.network, c.problem(),
                                        p.batches[static_cast<std::size_t>(kCompared + a)],
                                        UpdateNeed::kStackedJacobian, other));
            }
          }
          delta = rule->step(evaluated).delta;
          products = rule_spec(variant.rule).products;
        }
        const double cos = delta.dot(reference) / (delta.norm() * reference.norm());
        cos_sum[point] += cos;
        cos_min = std::min(cos_min, cos);
        const double before = mean_loss(p.network, c.problem(), batch);
        Mlp moved = p.network;
        moved.parameters() += delta;
        const double after = mean_loss(moved, c.problem(), batch);
        moved.parameters() = p.network.parameters() + reference;
        drop_sum[point] += (before - after) / (before - mean_loss(moved, c.problem(), batch));
      }
    }
  }
  state.counters["cos_init"] = cos_sum[0] / kCompared;
  state.counters["cos_trained"] = cos_sum[1] / kCompared;
  state.counters["cos_min"] = cos_min;
  state.counters["drop_init"] = drop_sum[0] / kCompared;
  state.counters["drop_trained"] = drop_sum[1] / kCompared;
  state.counters["products"] = static_cast<double>(products);
  state.SetLabel(std::string(case_spec(which).label) + " " + variant.label);
}

}  // namespace

// Per case: Adam, exact HIG (2 iterations at batch 64: ~8 s each), and the structured rules.
BENCHMARK(structured_step)
    ->ArgsProduct({{0, 1, 2}, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(structured_step)
    ->ArgsProduct({{3}, {0, 2, 3, 4, 5, 6, 7, 8, 9}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(structured_step)->Args({3, 1})->Iterations(2)->Unit(benchmark::kMillisecond);
BENCHMARK(structured_cosine)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) { return physgrad::bench::run_single_thread_benchmarks(argc, argv); }
