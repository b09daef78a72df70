#include "bench_command.hpp"

#include <lapacke.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <nlohmann/json.hpp>
#include <vector>

#include "physgrad/run/life/experiment.hpp"
#include "registry.hpp"
#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/text.hpp"
#include "physgrad/threads.hpp"

namespace physgrad::cli {

namespace {

namespace ex = physgrad::run;
using physgrad::experiments::builtin_registry;
using Clock = std::chrono::steady_clock;

constexpr double kMaxSteps = 1e6;  // timed or warm-up steps (their sum stays far from overflow)

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

long long read_integer(const std::string& name, const std::string& text, double at_least,
                       double at_most = std::numeric_limits<double>::infinity()) {
  return ex::parse_option(ex::integer_option(name, "", "").at_least(at_least).at_most(at_most),
                          text)
      .get<long long>();
}

// Median seconds of dsyevd (all eigenpairs) on a symmetric positive definite n × n matrix.
double eigendecomposition_seconds(Index n, long long repeats) {
  const Matrix a = Matrix::Random(n, n);
  const Matrix sym = a * a.transpose();
  Vector lambda(n);
  std::vector<double> times;
  for (long long r = 0; r < repeats; ++r) {
    Matrix w = sym;
    const auto start = Clock::now();
    const lapack_int status = LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'L', static_cast<lapack_int>(n),
                                             w.data(), static_cast<lapack_int>(n), lambda.data());
    times.push_back(seconds_since(start));
    if (status != 0) throw Error("bench: dsyevd failed (info = " + std::to_string(status) + ")");
  }
  return median(times);
}

// The batch: the rule's own in the experiment (as `physgrad run NAME` uses it) unless `given`.
// The reference eigendecomposition holds three B·m × B·m matrices and dsyevd's workspace of
// about two more; a batch for which they cannot fit is refused before anything is allocated.
Index bench_batch(const ex::ReferenceCase& single, const std::string& optimizer,
                  const std::string& given) {
  const Index batch =
      given.empty() ? single.batch_size(optimizer) : read_integer("batch", given, 1);
  const double order =
      static_cast<double>(batch) * static_cast<double>(single.physics->output_dim());
  char size[64];
  std::snprintf(size, sizeof size, "%.0f × %.0f", order, order);
  require_memory(5 * order * order * sizeof(double),
                 "--batch: " + std::to_string(batch) +
                     " (the reference eigendecomposition of a " + size + " matrix)");
  return batch;
}

// The seconds of each timed step: in all, forming J, inverting, the rule's own work, the rest.
struct StepTimes {
  std::vector<double> total, jacobian, inverse, rule, other;
};

// `warmup` untimed steps, then `steps` timed ones; a step not applied is an Error naming `what`.
StepTimes time_steps(ex::ReferenceCase& reference, LearningUpdate& update, long long warmup,
                     long long steps, const std::string& what) {
  const LearningProblem problem = reference.problem();
  StepTimes times;
  StepState step_state;
  for (long long s = 0; s < warmup + steps; ++s) {
    const StepReport report =
        train_step(reference.network, update, problem, reference.batch, step_state);
    if (!report.applied()) {
      throw Error("bench: step " + std::to_string(s + 1) + " of " + what + ": " +
                  describe_failure(report, s));
    }
    if (s < warmup) continue;
    times.total.push_back(report.total_seconds);
    times.jacobian.push_back(report.derivative_seconds);
    times.inverse.push_back(report.inversion_seconds);
    times.rule.push_back(report.update_seconds);
    times.other.push_back(std::max(0.0, report.total_seconds - report.derivative_seconds -
                                            report.inversion_seconds - report.update_seconds));
  }
  return times;
}

}  // namespace

BenchCommand::BenchCommand(CLI::App& app)
    : command_(app.add_subcommand(
          "bench", "time steps of an update on a reference experiment, one JSON line: physgrad bench "
                   "NAME [--optimizer U] [--batch B] [--steps N] [--warmup W] [--threads T]")) {
  command_->add_option("NAME", name_,
                       "reference experiment: " +
                           comma_list(builtin_registry().reference_names()))
      ->required();
  command_->add_option("--optimizer", optimizer_,
                       "update rule: " + comma_list(rule_ids(RuleKind::kLearning)))
      ->default_str(optimizer_);
  command_->add_option("--batch", batch_, "batch size (default: the rule's own in NAME)")
      ->type_name("INT");
  command_->add_option("--steps", steps_, "timed steps (1 to 1000000)")
      ->default_str(steps_)
      ->type_name("INT");
  command_->add_option("--warmup", warmup_, "untimed steps before (0 to 1000000)")
      ->default_str(warmup_)
      ->type_name("INT");
  command_->add_option("--threads", threads_,
                       "threads for the m physics VJPs of the stacked Jacobian (1 to 1024)")
      ->default_str(threads_)
      ->type_name("INT");
}

void BenchCommand::run(std::ostream& out) const {
  const long long steps = read_integer("steps", steps_, 1, kMaxSteps);
  const long long warmup = read_integer("warmup", warmup_, 0, kMaxSteps);
  const long long threads = read_integer("threads", threads_, 1, 1024);
  // The case at one sample: throws for an unknown NAME, naming the known ones.
  const ex::ReferenceCase single = builtin_registry().reference(name_, 1);
  find_rule(RuleKind::kLearning, optimizer_);  // throws for an unknown rule, naming the known ones
  if (std::getenv("OPENBLAS_NUM_THREADS") == nullptr && std::getenv("OMP_NUM_THREADS") == nullptr) {
    set_blas_threads(1);
  }
  set_jacobian_threads(static_cast<int>(threads));

  const Index batch = bench_batch(single, optimizer_, batch_);
  ex::ReferenceCase reference = builtin_registry().reference(name_, batch);
  const auto update = reference.update(optimizer_);
  const Mlp& network = reference.network;

  const StepTimes times =
      time_steps(reference, *update, warmup, steps, optimizer_ + " on " + name_);
  const Index rows = reference.batch.size() * reference.physics->output_dim();
  std::string backend = "none";
  nlohmann::json rank = nullptr;
  if (const auto* inverse_rule = dynamic_cast<const HigUpdate*>(update.get())) {
    backend = to_string(inverse_rule->last_info().backend);
    rank = inverse_rule->last_info().rank;
  } else if (optimizer_ == "sip") {
    backend = "local inverse";
  }
  // At most 5 repeats: at B·m = 4096 one takes seconds.
  const double reference_seconds = eigendecomposition_seconds(rows, std::min(steps, 5LL));
  const double per_step = median(times.total);
  nlohmann::json line = {
      {"experiment", name_},
      {"optimizer", optimizer_},
      {"batch", batch},
      {"steps", steps},
      {"warmup", warmup},
      {"threads", threads},
      {"blas_core", blas_core()},
      {"seconds_per_step", per_step},
      {"split",
       {{"jacobian", median(times.jacobian)},
        {"inverse", median(times.inverse)},
        {"update", median(times.rule)},
        {"other", median(times.other)}}},
      {"jacobian_shape", {rows, network.num_parameters()}},
      {"backend", backend},
      {"rank", rank},
      {"reference_linalg", {{"operation", "dsyevd"}, {"n", rows}, {"seconds", reference_seconds}}},
      {"step_over_reference", per_step / reference_seconds},
  };
  out << line.dump() << '\n';
}

}  // namespace physgrad::cli
