// The Kronecker-factored rules on ConvNetwork's U-net of heat-inverse (64×64 cells, 4 levels, 16
// filters, no batch norm): the conv layers' factor statistics against the network's own gradient
// for the same K cotangents per sample, and a kfac-hig update (refreshing, and between refreshes)
// against an Adam update. Args: batch B, cotangents per sample K (the physics outputs m a refresh
// sweeps; heat-inverse has m = 4096, here K random output directions stand in for them).
// BM_HeatKfacHigSampled: whole training steps on heat-inverse's own physics (64×64 heat
// diffusion) with kfac-hig's option samples = K, against Adam steps interleaved with them.
#include <benchmark/benchmark.h>

#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include "physgrad/catalogue.hpp"
#include "physgrad/learn/stacked_jacobian.hpp"
#include "physgrad/nn/conv_net.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "physgrad/physics/heat_diffusion.hpp"
#include "physgrad/train/trainer.hpp"
#include "single_thread_main.hpp"

namespace physgrad {
namespace {

// The U-net at initialisation, a batch of B inputs in [0, 1) and forward() run on it.
struct UNetBatch {
  ConvNetwork net = ConvNetwork::unet(UNetOptions{});
  Matrix x;
  std::unique_ptr<NetworkCache> cache = net.new_cache();
  Matrix output;

  explicit UNetBatch(Index batch) {
    net.initialize(1);
    x = (Matrix::Random(net.input_dim(), batch).array() + 1.0) / 2.0;
    output = net.forward(x, *cache);
  }
  // K cotangent matrices at the output (output_dim × B each).
  std::vector<Matrix> cotangents(Index count) const {
    std::vector<Matrix> out;
    for (Index k = 0; k < count; ++k) out.push_back(Matrix::Random(net.output_dim(), x.cols()));
    return out;
  }
};

Index bench_batch(const benchmark::State& state) { return state.range(0); }
Index bench_cotangents(const benchmark::State& state) { return state.range(1); }

// K backward sweeps of the cached batch: the network's gradient for each cotangent matrix.
void BM_UNetGradients(benchmark::State& state) {
  const UNetBatch u(bench_batch(state));
  const std::vector<Matrix> gys = u.cotangents(bench_cotangents(state));
  for (auto _ : state) {
    for (const Matrix& gy : gys) benchmark::DoNotOptimize(u.net.backward(*u.cache, gy));
  }
}

// The factors of every conv layer for the same K cotangent matrices.
void BM_UNetFactors(benchmark::State& state) {
  const UNetBatch u(bench_batch(state));
  const std::vector<Matrix> gys = u.cotangents(bench_cotangents(state));
  for (auto _ : state) benchmark::DoNotOptimize(u.net.dense_layer_factors(*u.cache, gys));
}

// One Adam update: forward, backward of the loss cotangent, the rule's step.
void BM_UNetAdamUpdate(benchmark::State& state) {
  UNetBatch u(bench_batch(state));
  const Matrix gy = u.cotangents(1).front();
  auto adam = make_learning_update("adam");
  BatchState batch;
  batch.batch_size = u.x.cols();
  for (auto _ : state) {
    u.net.forward(u.x, *u.cache);
    batch.gradient = u.net.backward(*u.cache, gy);
    benchmark::DoNotOptimize(adam->step(batch).delta);
  }
}

// One kfac-hig update that refreshes the factors: forward, ∇θ, the factors for K output
// directions, their eigendecompositions and the two products per layer.
void BM_UNetKfacHigRefresh(benchmark::State& state) {
  UNetBatch u(bench_batch(state));
  const Index count = bench_cotangents(state);
  const DiagonalScale directions(Vector::Ones(count));  // only its output count is used
  auto rule = make_learning_update("kfac-hig", {{"refresh", 1}});
  BatchState batch;
  batch.batch_size = u.x.cols();
  batch.loss_gradient_y = Vector::Random(count * u.x.cols());
  for (auto _ : state) {
    u.output = u.net.forward(u.x, *u.cache);
    batch.jacobian = std::make_shared<LocalJacobian>(u.net, *u.cache, directions, u.output,
                                                     u.cotangents(count));
    benchmark::DoNotOptimize(rule->step(batch).delta);
  }
}

// One kfac-hig update between refreshes: forward, backward, the two products per layer.
void BM_UNetKfacHigBetween(benchmark::State& state) {
  UNetBatch u(bench_batch(state));
  const DiagonalScale directions(Vector::Ones(1));
  auto rule = make_learning_update("kfac-hig", {{"refresh", 1000000}});
  BatchState first;
  first.batch_size = u.x.cols();
  first.loss_gradient_y = Vector::Random(u.x.cols());
  first.jacobian = std::make_shared<LocalJacobian>(u.net, *u.cache, directions, u.output,
                                                   u.cotangents(1));
  rule->step(first);  // the factors, once
  const Matrix gy = u.cotangents(1).front();
  BatchState batch;
  batch.batch_size = u.x.cols();
  for (auto _ : state) {
    u.net.forward(u.x, *u.cache);
    batch.gradient = u.net.backward(*u.cache, gy);
    benchmark::DoNotOptimize(rule->step(batch).delta);
  }
}

// CPU seconds of this process (every thread) spent in f().
template <typename F>
double cpu_seconds_of(const F& f) {
  timespec start{}, end{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &start);
  f();
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &end);
  return static_cast<double>(end.tv_sec - start.tv_sec) +
         1e-9 * static_cast<double>(end.tv_nsec - start.tv_nsec);
}

// One training step of `rule` on the heat-inverse problem (train_step: forward, physics, the
// rule's derivatives and step); its CPU seconds. Aborts the benchmark on a failed step.
double heat_step_seconds(benchmark::State& state, Network& net, LearningUpdate& rule,
                         const LearningProblem& problem, const Dataset& batch, StepState& steps) {
  StepReport report;
  const double seconds =
      cpu_seconds_of([&] { report = train_step(net, rule, problem, batch, steps); });
  if (!report.applied()) state.SkipWithError(describe_failure(report, 0).c_str());
  return seconds;
}

// Per iteration: an Adam update, then a kfac-hig update that refreshes its factors from K
// sampled output directions per sample, then one between refreshes (all on the same batch of B
// observed fields, targets y* = the observation as heat-inverse's loss ½‖P(f(y*)) − y*‖²).
// Counters in CPU ms and in Adam updates; amortised over refresh 10: (refresh + 9·between)/10.
void BM_HeatKfacHigSampled(benchmark::State& state) {
  const Index batch_size = bench_batch(state), samples = bench_cotangents(state);
  const HeatDiffusion physics(HeatConfig{.n = 64, .dims = 2, .amount = 8});
  const L2Loss loss(1.0);
  const LearningProblem problem{&physics, &loss};
  const Matrix fields = (Matrix::Random(physics.input_dim(), batch_size).array() + 1.0) / 2.0;
  const Dataset batch{fields, physics.forward_batch(fields, Matrix()), Matrix()};
  ConvNetwork adam_net = ConvNetwork::unet(UNetOptions{});
  adam_net.initialize(1);
  ConvNetwork rule_net = adam_net;
  auto adam = make_learning_update("adam");
  // η small enough that the steps stay finite (at hig's η = 1 the first step makes the loss
  // non-finite); the cost of a step does not depend on it.
  auto refreshing = make_learning_update(
      "kfac-hig", {{"lr", 1e-5}, {"refresh", 1}, {"samples", samples}});
  auto between = make_learning_update(
      "kfac-hig", {{"lr", 1e-5}, {"refresh", 1000000}, {"samples", samples}});
  StepState adam_steps, refresh_steps, between_steps;
  // The between-refreshes rule takes its factors once, outside the timing.
  train_step(rule_net, *between, problem, batch, between_steps);
  double adam_total = 0, refresh_total = 0, between_total = 0, count = 0;
  for (auto _ : state) {
    adam_total += heat_step_seconds(state, adam_net, *adam, problem, batch, adam_steps);
    refresh_total += heat_step_seconds(state, rule_net, *refreshing, problem, batch, refresh_steps);
    between_total += heat_step_seconds(state, rule_net, *between, problem, batch, between_steps);
    ++count;
  }
  const double a = adam_total / count, r = refresh_total / count, b = between_total / count;
  state.counters["adam_cpu_ms"] = 1e3 * a;
  state.counters["refresh_cpu_ms"] = 1e3 * r;
  state.counters["between_cpu_ms"] = 1e3 * b;
  state.counters["refresh_adam"] = r / a;
  state.counters["between_adam"] = b / a;
  state.counters["amortised10_adam"] = (r + 9 * b) / 10 / a;
  state.SetLabel("B " + std::to_string(batch_size) + ", K " + std::to_string(samples));
}

constexpr int kRepeats = 2;
BENCHMARK(BM_UNetGradients)->Args({32, 1})->Args({32, 16})->Unit(benchmark::kMillisecond)
    ->Iterations(kRepeats);
BENCHMARK(BM_UNetFactors)->Args({32, 1})->Args({32, 16})->Unit(benchmark::kMillisecond)
    ->Iterations(kRepeats);
BENCHMARK(BM_UNetAdamUpdate)->Args({32, 0})->Unit(benchmark::kMillisecond)->Iterations(kRepeats);
BENCHMARK(BM_UNetKfacHigBetween)->Args({32, 0})->Unit(benchmark::kMillisecond)
    ->Iterations(kRepeats);
BENCHMARK(BM_UNetKfacHigRefresh)->Args({32, 1})->Args({32, 16})->Unit(benchmark::kMillisecond)
    ->Iterations(kRepeats);
BENCHMARK(BM_HeatKfacHigSampled)->Args({128, 1})->Args({128, 4})->Args({128, 16})
    ->Unit(benchmark::kMillisecond)->Iterations(kRepeats);

}  // namespace
}  // namespace physgrad

int main(int argc, char** argv) { return physgrad::bench::run_single_thread_benchmarks(argc, argv); }
