// CheckedSimulator — a user's Simulator as the library sees it: every call forwarded, the size of
// every returned value checked, the work counted (passes = forward + VJP + m·J + 2n·H + R + P⁻¹).
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/physics/simulator.hpp"

namespace physgrad {

// The work a simulator did, as calls and samples reached it.
struct SimulatorCounts {
  long long forward = 0;    // samples through forward_batch (one per column)
  long long vjp = 0;        // samples through vjp_batch
  long long jacobians = 0;  // jacobian() calls
  long long hessians = 0;   // weighted_hessian() calls
  long long reversals = 0;  // time_reversal() calls
  long long inverses = 0;   // inverse() calls
  // Single-sample passes: forward + vjp + m·jacobians + 2n·hessians + reversals + inverses. A
  // Jacobian counts as the m VJPs and a weighted Hessian as the VJP of 2n points that their
  // default implementations make, whatever the simulator does instead; a time reversal or an
  // inverse counts as one pass.
  long long passes = 0;

  // Every count with its name ("forward", "vjp", …, "passes"), for sums and files.
  static const std::array<std::pair<const char*, long long SimulatorCounts::*>, 7>& fields();
  SimulatorCounts& operator+=(const SimulatorCounts& other);
  SimulatorCounts& operator-=(const SimulatorCounts& other);
  friend SimulatorCounts operator-(SimulatorCounts a, const SimulatorCounts& b) { return a -= b; }
  bool operator==(const SimulatorCounts&) const = default;
};
// "664 passes (434 forward, 230 VJP)": the passes, then the nonzero counts.
std::string to_string(const SimulatorCounts& counts);

class SimulatorBudget;

// Forwards every member to the simulator it wraps and checks what comes back: input_dim() and
// output_dim() ≥ 1 and context_dim() ≥ 0 (read once, at construction: the library sees these
// values throughout), and the shape of every result — forward_batch m×B, vjp_batch n×B,
// jacobian m×n, weighted_hessian n×n, inverse and time_reversal n entries — or throws Error
// "simulator 'NAME': jacobian returned 0×0, expected 2×4". Values are not inspected (a NaN is the
// numerical guards' business). Exceptions of the wrapped simulator pass through unchanged.
//
// It counts the work (counts(); thread-safe: the learning rules call vjp_batch on several
// threads) and enforces the budgets opened on it (SimulatorBudget): a call that would exceed one
// is not made, BudgetExhausted is thrown instead. minimize(), local_inverse(), train_step(),
// mean_loss() and check_derivatives() put one around the simulator they are given, unless it is
// one already (then the work of a nested call — the local inverse of a pg step — counts toward
// the outer run and its budget).
class CheckedSimulator final : public Simulator {
 public:
  explicit CheckedSimulator(const Simulator& inner);
  CheckedSimulator(const CheckedSimulator&) = delete;
  CheckedSimulator& operator=(const CheckedSimulator&) = delete;

  // `simulator` itself when it is a CheckedSimulator, else one emplaced into `local` around it.
  static const CheckedSimulator& around(const Simulator& simulator,
                                        std::optional<CheckedSimulator>& local);

  const Simulator& inner() const { return *inner_; }
  SimulatorCounts counts() const;

  std::string name() const override { return inner_->name(); }
  Index input_dim() const override { return n_; }
  Index output_dim() const override { return m_; }
  Index context_dim() const override { return context_dim_; }
  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;
  Matrix jacobian(const Vector& x, const Vector& context = {}) const override;
  bool has_jacobian() const override { return has_jacobian_; }
  Matrix weighted_hessian(const Vector& x, const Vector& context, const Vector& w) const override;
  bool has_inverse() const override { return has_inverse_; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector& context = {}) const override;
  bool has_time_reversal() const override { return has_time_reversal_; }
  Vector time_reversal(const Vector& y, const Vector& context = {}) const override;

 private:
  friend class SimulatorBudget;
  // Checks the open budgets for `passes` more, then adds `amount` to `counter` and the passes.
  void charge(std::atomic<long long>& counter, long long amount, long long passes) const;
  // Throw Error unless `result` is rows×cols, or has `size` entries.
  void check_result(const char* method, const Matrix& result, Index rows, Index cols) const;
  void check_result(const char* method, const Vector& result, Index size) const;

  const Simulator* inner_;
  Index n_, m_, context_dim_;
  bool has_jacobian_, has_inverse_, has_time_reversal_;
  mutable std::atomic<long long> forward_{0}, vjp_{0}, jacobians_{0}, hessians_{0}, reversals_{0},
      inverses_{0}, passes_{0};
  mutable std::vector<const SimulatorBudget*> budgets_;  // open budgets, innermost last
};

// A limit on the passes and the wall time of one run on a CheckedSimulator, open from its
// construction to its destruction (budgets nest: each is checked before every call). 0: no limit.
// Budgets are opened and closed by the thread that runs the calls (minimize()): one run at a
// time on a CheckedSimulator.
class SimulatorBudget {
 public:
  using Clock = std::chrono::steady_clock;
  // The run started at `start` with the simulator's passes at `passes_at_start`.
  SimulatorBudget(const CheckedSimulator& simulator, long long max_passes, double max_seconds,
                  long long passes_at_start, Clock::time_point start);
  ~SimulatorBudget();
  SimulatorBudget(const SimulatorBudget&) = delete;
  SimulatorBudget& operator=(const SimulatorBudget&) = delete;

  bool out_of_time() const;
  // Throws BudgetExhausted unless `cost` more passes fit after `passes` and time remains.
  void check(long long passes, long long cost) const;

 private:
  const CheckedSimulator& simulator_;
  long long max_passes_;
  double max_seconds_;
  long long passes_at_start_;
  Clock::time_point start_;
};

// A budget ran out: the call was not made. The run that opened `budget` ends on it; any other
// code lets it pass.
class BudgetExhausted final : public Error {
 public:
  enum class Kind { kPasses, kSeconds };
  BudgetExhausted(const SimulatorBudget* budget, Kind kind, const std::string& message)
      : Error(message), budget_(budget), kind_(kind) {}
  const SimulatorBudget* budget() const { return budget_; }
  Kind kind() const { return kind_; }

 private:
  const SimulatorBudget* budget_;
  Kind kind_;
};

}  // namespace physgrad
