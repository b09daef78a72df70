#include "physgrad/physics/checked_simulator.hpp"

#include <algorithm>
#include <sstream>
#include <utility>

namespace physgrad {

namespace {

// Reads one dimension of `inner`, which must be at least `least`.
Index simulator_dim(const Simulator& inner, Index value, const char* what, Index least) {
  if (value < least) {
    std::ostringstream msg;
    msg << "simulator '" << inner.name() << "': " << what << "() returned " << value
        << ", expected ≥ " << least;
    throw Error(msg.str());
  }
  return value;
}

}  // namespace

const std::array<std::pair<const char*, long long SimulatorCounts::*>, 7>&
SimulatorCounts::fields() {
  static constexpr std::array<std::pair<const char*, long long SimulatorCounts::*>, 7> kFields{{
      {"forward", &SimulatorCounts::forward},
      {"vjp", &SimulatorCounts::vjp},
      {"jacobians", &SimulatorCounts::jacobians},
      {"hessians", &SimulatorCounts::hessians},
      {"reversals", &SimulatorCounts::reversals},
      {"inverses", &SimulatorCounts::inverses},
      {"passes", &SimulatorCounts::passes},
  }};
  return kFields;
}

SimulatorCounts& SimulatorCounts::operator+=(const SimulatorCounts& other) {
  for (const auto& [name, field] : fields()) this->*field += other.*field;
  return *this;
}

SimulatorCounts& SimulatorCounts::operator-=(const SimulatorCounts& other) {
  for (const auto& [name, field] : fields()) this->*field -= other.*field;
  return *this;
}

std::string to_string(const SimulatorCounts& counts) {
  std::ostringstream out;
  out << counts.passes << " passes";
  const std::pair<long long, const char*> parts[] = {
      {counts.forward, "forward"},     {counts.vjp, "VJP"},
      {counts.jacobians, "Jacobians"}, {counts.hessians, "Hessians"},
      {counts.reversals, "reversals"}, {counts.inverses, "inverses"}};
  bool first = true;
  for (const auto& [count, what] : parts) {
    if (count == 0) continue;
    out << (first ? " (" : ", ") << count << " " << what;
    first = false;
  }
  if (!first) out << ")";
  return out.str();
}

CheckedSimulator::CheckedSimulator(const Simulator& inner)
    : inner_(&inner),
      n_(simulator_dim(inner, inner.input_dim(), "input_dim", 1)),
      m_(simulator_dim(inner, inner.output_dim(), "output_dim", 1)),
      context_dim_(simulator_dim(inner, inner.context_dim(), "context_dim", 0)),
      has_jacobian_(inner.has_jacobian()),
      has_inverse_(inner.has_inverse()),
      has_time_reversal_(inner.has_time_reversal()) {}

const CheckedSimulator& CheckedSimulator::around(const Simulator& simulator,
                                                 std::optional<CheckedSimulator>& local) {
  if (const auto* checked = dynamic_cast<const CheckedSimulator*>(&simulator)) return *checked;
  return local.emplace(simulator);
}

SimulatorCounts CheckedSimulator::counts() const {
  return {forward_.load(), vjp_.load(),       jacobians_.load(), hessians_.load(),
          reversals_.load(), inverses_.load(), passes_.load()};
}

void CheckedSimulator::charge(std::atomic<long long>& counter, long long amount,
                              long long passes) const {
  if (!budgets_.empty()) {
    const long long spent = passes_.load();
    for (const SimulatorBudget* budget : budgets_) budget->check(spent, passes);
  }
  counter += amount;
  passes_ += passes;
}

void CheckedSimulator::check_result(const char* method, const Matrix& result, Index rows,
                                    Index cols) const {
  if (result.rows() == rows && result.cols() == cols) return;
  throw_wrong_result("simulator '" + name() + "'", method, result.rows(), result.cols(), rows,
                     cols);
}

void CheckedSimulator::check_result(const char* method, const Vector& result, Index size) const {
  if (result.size() == size) return;
  throw_wrong_result("simulator '" + name() + "'", method, result.size(), -1, size, -1);
}

Matrix CheckedSimulator::forward_batch(const Matrix& x, const Matrix& context) const {
  charge(forward_, x.cols(), x.cols());
  Matrix y = inner_->forward_batch(x, context);
  check_result("forward_batch", y, m_, x.cols());
  return y;
}

Matrix CheckedSimulator::vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const {
  charge(vjp_, x.cols(), x.cols());
  Matrix gx = inner_->vjp_batch(x, context, gy);
  check_result("vjp_batch", gx, n_, x.cols());
  return gx;
}

Matrix CheckedSimulator::jacobian(const Vector& x, const Vector& context) const {
  charge(jacobians_, 1, m_);
  Matrix j = inner_->jacobian(x, context);
  check_result("jacobian", j, m_, n_);
  return j;
}

Matrix CheckedSimulator::weighted_hessian(const Vector& x, const Vector& context,
                                          const Vector& w) const {
  charge(hessians_, 1, 2 * n_);
  Matrix h = inner_->weighted_hessian(x, context, w);
  check_result("weighted_hessian", h, n_, n_);
  return h;
}

Vector CheckedSimulator::inverse(const Vector& y, const Vector& x0, const Vector& context) const {
  charge(inverses_, 1, 1);
  Vector x = inner_->inverse(y, x0, context);
  check_result("inverse", x, n_);
  return x;
}

Vector CheckedSimulator::time_reversal(const Vector& y, const Vector& context) const {
  charge(reversals_, 1, 1);
  Vector x = inner_->time_reversal(y, context);
  check_result("time_reversal", x, n_);
  return x;
}

SimulatorBudget::SimulatorBudget(const CheckedSimulator& simulator, long long max_passes,
                                 double max_seconds, long long passes_at_start,
                                 Clock::time_point start)
    : simulator_(simulator),
      max_passes_(max_passes),
      max_seconds_(max_seconds),
      passes_at_start_(passes_at_start),
      start_(start) {
  if (max_passes_ > 0 || max_seconds_ > 0) simulator_.budgets_.push_back(this);
}

SimulatorBudget::~SimulatorBudget() {
  auto& open = simulator_.budgets_;
  open.erase(std::remove(open.begin(), open.end(), this), open.end());
}

bool SimulatorBudget::out_of_time() const {
  return max_seconds_ > 0 &&
         std::chrono::duration<double>(Clock::now() - start_).count() >= max_seconds_;
}

void SimulatorBudget::check(long long passes, long long cost) const {
  if (max_passes_ > 0 && passes - passes_at_start_ + cost > max_passes_) {
    throw BudgetExhausted(this, BudgetExhausted::Kind::kPasses,
                          std::to_string(passes - passes_at_start_) + " of " +
                              std::to_string(max_passes_) +
                              " simulator passes spent, the next call needs " +
                              std::to_string(cost));
  }
  if (out_of_time()) {
    std::ostringstream msg;
    msg << max_seconds_ << " seconds spent";
    throw BudgetExhausted(this, BudgetExhausted::Kind::kSeconds, msg.str());
  }
}

}  // namespace physgrad
