// Lying models — a user's simulator (y = A x + b) and network (an Mlp) whose one method, from a
// planned call on, returns a wrong size, an empty result, NaN or Inf entries, or throws.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/physics/simulator.hpp"

namespace physgrad::testing {

// Thrown by value by a liar: not derived from std::exception.
struct NotAnException {
  int code = 0;
};

enum class Lie { kNone, kRows, kCols, kEmpty, kNaN, kInf, kThrowError, kThrowNumerical,
                 kThrowRuntime, kThrowOther };
inline constexpr Lie kLies[] = {Lie::kRows, Lie::kCols, Lie::kEmpty, Lie::kNaN, Lie::kInf,
                         Lie::kThrowError, Lie::kThrowNumerical, Lie::kThrowRuntime,
                         Lie::kThrowOther};
inline const char* to_text(Lie lie) {
  switch (lie) {
    case Lie::kNone: return "none";
    case Lie::kRows: return "rows";
    case Lie::kCols: return "cols";
    case Lie::kEmpty: return "empty";
    case Lie::kNaN: return "nan";
    case Lie::kInf: return "inf";
    case Lie::kThrowError: return "throw Error";
    case Lie::kThrowNumerical: return "throw NumericalError";
    case Lie::kThrowRuntime: return "throw runtime_error";
    case Lie::kThrowOther: return "throw NotAnException";
  }
  return "";
}
inline bool wrong_size(Lie lie) { return lie == Lie::kRows || lie == Lie::kCols || lie == Lie::kEmpty; }

// What a liar did: the first wrong value it returned (method and kind), and what it threw.
struct Conduct {
  std::string lied_in;  // method of the first wrong value returned, empty: none
  Lie lie = Lie::kNone;
  Lie thrown = Lie::kNone;
  bool lied() const { return !lied_in.empty(); }
};

// One lie: a method, what it returns, from which of its calls on.
struct Plan {
  std::string method;
  Lie lie = Lie::kNone;
  int from = 0;
};

// Spoils the results of one method as planned.
class Liar {
 public:
  Liar(const Plan& plan, std::uint64_t seed, Conduct& conduct)
      : method_(plan.method), lie_(plan.lie), from_(plan.from), rng_(seed), conduct_(&conduct) {}

  // `value` as method `method` returns it this time.
  Matrix spoil(const char* method, Matrix value, bool is_vector = false) const {
    if (method_ != method || calls_++ < from_ || lie_ == Lie::kNone) return value;
    switch (lie_) {
      case Lie::kThrowError: throw_now(Lie::kThrowError); break;
      case Lie::kThrowNumerical: throw_now(Lie::kThrowNumerical); break;
      case Lie::kThrowRuntime: throw_now(Lie::kThrowRuntime); break;
      case Lie::kThrowOther: throw_now(Lie::kThrowOther); break;
      case Lie::kNaN:
      case Lie::kInf:
        if (value.size() == 0) return value;
        value(static_cast<Index>(draw() % static_cast<std::uint64_t>(value.size()))) =
            lie_ == Lie::kNaN ? std::numeric_limits<double>::quiet_NaN()
                              : (draw() % 2 ? 1.0 : -1.0) * std::numeric_limits<double>::infinity();
        break;
      case Lie::kEmpty: value.resize(0, is_vector ? 1 : 0); break;
      case Lie::kRows:
      case Lie::kCols: {
        const bool rows = lie_ == Lie::kRows || is_vector;
        const Index old = rows ? value.rows() : value.cols();
        Index changed = old + static_cast<Index>(draw() % 4) + 1;
        if (old > 1 && draw() % 2 == 0) {
          changed = static_cast<Index>(draw() % static_cast<std::uint64_t>(old));
        }
        value = Matrix::Constant(rows ? changed : value.rows(), rows ? value.cols() : changed, 0.5);
        break;
      }
      case Lie::kNone: break;
    }
    if (!conduct_->lied()) {
      conduct_->lied_in = method;
      conduct_->lie = lie_;
    }
    return value;
  }
  Vector spoil_vector(const char* method, const Vector& value) const {
    const Matrix spoiled = spoil(method, value, true);
    return spoiled.size() == 0 ? Vector() : Vector(spoiled.reshaped());
  }

 private:
  [[noreturn]] void throw_now(Lie lie) const {
    conduct_->thrown = lie;
    switch (lie) {
      case Lie::kThrowError: throw Error("liar: " + method_ + " refuses");
      case Lie::kThrowNumerical: throw NumericalError("liar: " + method_ + " broke down");
      case Lie::kThrowRuntime: throw std::runtime_error("liar: " + method_ + " failed");
      default: throw NotAnException{7};
    }
  }
  std::uint64_t draw() const { return rng_(); }

  std::string method_;
  Lie lie_;
  int from_;
  mutable std::mt19937_64 rng_;
  Conduct* conduct_;
  mutable int calls_ = 0;
};

// A dimension as the liar reports it: honest, or from the planned call on 0 (an empty lie) or −1
// (any other; context_dim always −1).
inline Index lying_dim(const Liar& liar, const char* which, Index honest) {
  const Matrix spoiled = liar.spoil(which, Matrix::Constant(1, 1, static_cast<double>(honest)));
  if (spoiled.size() == 1 && spoiled(0, 0) == static_cast<double>(honest)) return honest;
  return spoiled.size() == 0 && std::string(which) != "context_dim" ? 0 : -1;
}

// Honestly y = A x + b (m×n, well conditioned): its inverse and time reversal are the minimum-norm
// preimages, its Hessian zero. The liar spoils one method, or the dimensions.
class LyingSimulator final : public Simulator {
 public:
  LyingSimulator(Matrix a, Vector b, const Liar& liar, bool inverse, bool reversal)
      : a_(std::move(a)),
        b_(std::move(b)),
        pinv_(a_.completeOrthogonalDecomposition().pseudoInverse()),
        liar_(liar), inverse_(inverse), reversal_(reversal) {}

  std::string name() const override { return "liar"; }
  Index input_dim() const override { return dim("input_dim", a_.cols()); }
  Index output_dim() const override { return dim("output_dim", a_.rows()); }
  Index context_dim() const override { return dim("context_dim", 0); }
  Matrix forward_batch(const Matrix& x, const Matrix& context) const override {
    check_batch(x, context, "forward_batch");
    return liar_.spoil("forward_batch", (a_ * x).colwise() + b_);
  }
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override {
    check_batch(x, context, "vjp_batch");
    return liar_.spoil("vjp_batch", a_.transpose() * gy);
  }
  Matrix jacobian(const Vector& /*x*/, const Vector& /*context*/) const override {
    return liar_.spoil("jacobian", a_);
  }
  Matrix weighted_hessian(const Vector& /*x*/, const Vector& /*context*/,
                          const Vector& /*w*/) const override {
    return liar_.spoil("weighted_hessian", Matrix::Zero(a_.cols(), a_.cols()));
  }
  bool has_inverse() const override { return inverse_; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector& /*context*/) const override {
    return liar_.spoil_vector("inverse", x0 + pinv_ * (y - a_ * x0 - b_));
  }
  bool has_time_reversal() const override { return reversal_; }
  Vector time_reversal(const Vector& y, const Vector& /*context*/) const override {
    return liar_.spoil_vector("time_reversal", pinv_ * (y - b_));
  }

 private:
  Index dim(const char* which, Index honest) const { return lying_dim(liar_, which, honest); }

  Matrix a_;
  Vector b_;
  Matrix pinv_;
  const Liar& liar_;
  bool inverse_, reversal_;
};

// An Mlp whose results the liar spoils.
class LyingNetwork final : public Network {
 public:
  LyingNetwork(Mlp mlp, const Liar& liar) : mlp_(std::move(mlp)), liar_(liar) {}
  Index input_dim() const override {
    return lying_dim(liar_, "network input_dim", mlp_.input_dim());
  }
  Index output_dim() const override {
    return lying_dim(liar_, "network output_dim", mlp_.output_dim());
  }
  Index num_parameters() const override {
    const Matrix n = liar_.spoil("num_parameters", Matrix::Constant(1, 1, 1.0));
    return mlp_.num_parameters() + (n.size() == 1 && n(0, 0) == 1.0 ? 0 : 1);
  }
  const Vector& parameters() const override { return mlp_.parameters(); }
  Vector& parameters() override { return mlp_.parameters(); }
  std::unique_ptr<NetworkCache> new_cache() const override {
    const Matrix keep = liar_.spoil("new_cache", Matrix::Constant(1, 1, 1.0));
    if (keep.size() == 1 && keep(0, 0) == 1.0) return mlp_.new_cache();
    return nullptr;
  }
  Matrix forward(const Matrix& x, NetworkCache& cache) const override {
    return liar_.spoil("network forward", mlp_.forward(x, cache));
  }
  Vector backward(const NetworkCache& cache, const Matrix& gy) const override {
    return liar_.spoil_vector("backward", mlp_.backward(cache, gy));
  }
  void per_sample_gradients(const NetworkCache& cache, const Matrix& gy,
                            StridedMatrixRef out) const override {
    mlp_.per_sample_gradients(cache, gy, out);
    // The block has its size: only its values can lie.
    const Matrix spoiled = liar_.spoil("per_sample_gradients", out);
    if (spoiled.rows() == out.rows() && spoiled.cols() == out.cols()) out = spoiled;
  }
  Matrix per_sample_gram(const NetworkCache& cache,
                         const std::vector<Matrix>& cotangents) const override {
    return liar_.spoil("per_sample_gram", mlp_.per_sample_gram(cache, cotangents));
  }

 private:
  Mlp mlp_;
  const Liar& liar_;
};

}  // namespace physgrad::testing
