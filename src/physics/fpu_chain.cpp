#include "physgrad/physics/fpu_chain.hpp"

#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/stop.hpp"

namespace physgrad {

FpuChain::FpuChain(FpuChainConfig config) : config_(config) {
  std::ostringstream msg;
  msg << "fpu_chain: ";
  if (config_.masses < 1) {
    msg << "needs at least one mass, got " << config_.masses;
  } else if (config_.steps < 1) {
    msg << "needs at least one step, got " << config_.steps;
  } else if (!(std::isfinite(config_.dt) && config_.dt > 0)) {
    msg << "dt must be finite and > 0, got " << config_.dt;
  } else if (!std::isfinite(config_.beta)) {
    msg << "beta must be finite, got " << config_.beta;
  } else {
    // A state has 2N values and a step's work arrays about 6N more; the product is taken in
    // double, so a chain whose 2N overflows Index is refused here too.
    require_memory(64.0 * static_cast<double>(config_.masses),
                   "fpu_chain: " + std::to_string(config_.masses) +
                       " masses (a state and its work arrays, 64 B per mass)");
    return;
  }
  throw Error(msg.str());
}

namespace {

// The N + 1 bond extensions d_b = q_{b+1} − q_b with the walls q₀ = q_{N+1} = 0.
Eigen::ArrayXXd bonds(const Eigen::ArrayXXd& q) {
  const Index N = q.rows(), B = q.cols();
  Eigen::ArrayXXd d(N + 1, B);
  d.row(0) = q.row(0);
  d.row(N) = -q.row(N - 1);
  if (N > 1) d.middleRows(1, N - 1) = q.bottomRows(N - 1) - q.topRows(N - 1);
  return d;
}

// Mass i feels +f of the bond to its right and −f of the bond to its left.
Eigen::ArrayXXd divergence(const Eigen::ArrayXXd& f) {
  const Index N = f.rows() - 1;
  return f.bottomRows(N) - f.topRows(N);
}

}  // namespace

FpuChain::Array FpuChain::acceleration(const Array& q) const {
  const Array d = bonds(q);
  return divergence(d + config_.beta * d.cube());
}

FpuChain::Array FpuChain::acceleration_jvp(const Array& q, const Array& lambda) const {
  return divergence((1 + 3 * config_.beta * bonds(q).square()) * bonds(lambda));
}

FpuChain::Array FpuChain::integrate(Array s, Array* positions) const {
  const Index N = config_.masses, B = s.cols();
  const double h = config_.dt;
  auto q = s.topRows(N);
  auto p = s.bottomRows(N);
  Array a = acceleration(q);
  for (Index n = 0; n < config_.steps; ++n) {
    throw_if_stop_requested("fpu_chain");
    if (positions) positions->middleCols(n * B, B) = q;
    p += (0.5 * h) * a;
    q += h * p;
    a = acceleration(q);
    p += (0.5 * h) * a;
  }
  if (positions) positions->middleCols(config_.steps * B, B) = q;
  return s;
}

Matrix FpuChain::forward_batch(const Matrix& x, const Matrix& context) const {
  check_batch(x, context, "forward");
  return integrate(x.array(), nullptr).matrix();
}

Matrix FpuChain::vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const {
  check_vjp_batch(x, context, gy);
  const Index N = config_.masses, B = x.cols();
  require_memory(8.0 * static_cast<double>(N) * (static_cast<double>(config_.steps) + 1) *
                     static_cast<double>(B),
                 name() + ".vjp: the positions of " + std::to_string(N) + " masses over " +
                     std::to_string(config_.steps) + " steps for " + std::to_string(B) +
                     " samples");
  Array positions(N, (config_.steps + 1) * B);
  integrate(x.array(), &positions);
  const auto at = [&](Index n) { return Array(positions.middleCols(n * B, B)); };

  // Reverse sweep of p½ = p + h/2 a(q), q' = q + h p½, p' = p½ + h/2 a(q'), with the
  // cotangents (λq, λp) of (q', p') turned into those of (q, p).
  const double h = config_.dt;
  Array lq = gy.topRows(N).array(), lp = gy.bottomRows(N).array();
  for (Index n = config_.steps - 1; n >= 0; --n) {
    throw_if_stop_requested("fpu_chain.vjp");
    lq += (0.5 * h) * acceleration_jvp(at(n + 1), lp);  // p' = p½ + h/2 a(q')
    lp += h * lq;                                       // q' = q + h p½
    lq += (0.5 * h) * acceleration_jvp(at(n), lp);      // p½ = p + h/2 a(q)
  }
  Matrix gx(2 * N, B);
  gx.topRows(N) = lq.matrix();
  gx.bottomRows(N) = lp.matrix();
  return gx;
}

Vector FpuChain::time_reversal(const Vector& y, const Vector& context) const {
  check_batch(y, context, "time_reversal");  // y, like x, is a state
  const Index N = config_.masses;
  // Flip the momenta, run the same steps forward, flip back.
  Array s = y.array();
  s.bottomRows(N) *= -1;
  s = integrate(std::move(s), nullptr);
  s.bottomRows(N) *= -1;
  return s.matrix();
}

}  // namespace physgrad
