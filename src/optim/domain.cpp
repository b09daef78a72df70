#include "physgrad/optim/domain.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

void check_bound_size(const Vector& v, Index n, const char* name) {
  if (v.size() != 0 && v.size() != n) {
    std::ostringstream msg;
    msg << "domain: " << name << " has " << v.size() << " entries, expected " << n
        << " (or none)";
    throw Error(msg.str());
  }
}

}  // namespace

Domain::Domain(Index n, Vector lower, Vector upper, Vector scale)
    : lower_(std::move(lower)), upper_(std::move(upper)), scale_(std::move(scale)) {
  check_bound_size(lower_, n, "lower");
  check_bound_size(upper_, n, "upper");
  check_bound_size(scale_, n, "x_scale");
  if (lower_.size() != 0 || upper_.size() != 0) {
    if (lower_.size() == 0) lower_ = Vector::Constant(n, -kInf);
    if (upper_.size() == 0) upper_ = Vector::Constant(n, kInf);
  }
  for (Index i = 0; i < lower_.size(); ++i) {
    std::ostringstream msg;
    if (std::isnan(lower_(i)) || lower_(i) == kInf) {
      msg << "domain: lower[" << i << "] = " << lower_(i) << " must be a number below +inf";
    } else if (std::isnan(upper_(i)) || upper_(i) == -kInf) {
      msg << "domain: upper[" << i << "] = " << upper_(i) << " must be a number above -inf";
    } else if (lower_(i) > upper_(i)) {
      msg << "domain: lower[" << i << "] = " << lower_(i) << " exceeds upper[" << i
          << "] = " << upper_(i);
    } else {
      continue;
    }
    throw Error(msg.str());
  }
  for (Index i = 0; i < scale_.size(); ++i) {
    if (!(std::isfinite(scale_(i)) && scale_(i) > 0)) {
      std::ostringstream msg;
      msg << "domain: x_scale[" << i << "] = " << scale_(i) << " must be finite and > 0";
      throw Error(msg.str());
    }
  }
}

Vector Domain::lower(Index n) const { return bounded() ? lower_ : Vector::Constant(n, -kInf); }
Vector Domain::upper(Index n) const { return bounded() ? upper_ : Vector::Constant(n, kInf); }
Vector Domain::scale(Index n) const { return scaled() ? scale_ : Vector::Ones(n); }

void Domain::check_dim(Index n, const char* where) const {
  const Index dim = std::max(lower_.size(), scale_.size());
  if (dim != 0 && dim != n) {
    std::ostringstream msg;
    msg << where << ": x has " << n << " entries, the domain (bounds, x_scale) " << dim;
    throw Error(msg.str());
  }
}

void Domain::check_contains(const Vector& x, const std::string& name) const {
  for (Index i = 0; i < x.size(); ++i) {
    std::ostringstream msg;
    if (std::isnan(x(i))) {
      msg << name << "[" << i << "] is NaN";
    } else if (bounded() && x(i) < lower_(i)) {
      msg << name << "[" << i << "] = " << x(i) << " is below its lower bound " << lower_(i);
    } else if (bounded() && x(i) > upper_(i)) {
      msg << name << "[" << i << "] = " << x(i) << " is above its upper bound " << upper_(i);
    } else {
      continue;
    }
    throw Error(msg.str());
  }
}

Vector Domain::project(const Vector& x) const {
  if (!bounded()) return x;
  return x.cwiseMax(lower_).cwiseMin(upper_);
}

Vector Domain::feasible_step(const Vector& x, const Vector& dx) const {
  if (!bounded()) return dx;
  return project(x + dx) - x;
}

std::vector<bool> Domain::free_variables(const Vector& x, const Vector& g) const {
  std::vector<bool> free(static_cast<std::size_t>(x.size()), true);
  if (!bounded()) return free;
  for (Index i = 0; i < x.size(); ++i) {
    const bool held = (x(i) <= lower_(i) && g(i) > 0) || (x(i) >= upper_(i) && g(i) < 0);
    free[static_cast<std::size_t>(i)] = !held;
  }
  return free;
}

double Domain::max_step(const Vector& x, const Vector& d) const {
  double alpha = kInf;
  if (!bounded()) return alpha;
  for (Index i = 0; i < x.size(); ++i) {
    if (d(i) > 0) alpha = std::min(alpha, (upper_(i) - x(i)) / d(i));
    if (d(i) < 0) alpha = std::min(alpha, (lower_(i) - x(i)) / d(i));
  }
  return std::max(alpha, 0.0);
}

double Domain::projected_gradient_norm(const Vector& x, const Vector& g) const {
  const Vector s = scale(x.size());
  const Vector moved = x - s.cwiseAbs2().cwiseProduct(g);
  return (x - project(moved)).cwiseQuotient(s).lpNorm<Eigen::Infinity>();
}

double Domain::scaled_norm(const Vector& v) const {
  return scaled() ? v.cwiseQuotient(scale_).norm() : v.norm();
}

Index Domain::count_at_bounds(const Vector& x) const {
  if (!bounded()) return 0;
  return ((x.array() <= lower_.array()) || (x.array() >= upper_.array())).count();
}

FreeSubspace::FreeSubspace(const Domain& domain, const Vector& x, const Vector& g)
    : domain_(domain), x_(x), scale_(domain.scale(x.size())) {
  const std::vector<bool> free = domain.free_variables(x, g);
  for (Index i = 0; i < x.size(); ++i) {
    if (free[static_cast<std::size_t>(i)]) index_.push_back(i);
  }
}

Vector FreeSubspace::covector(const Vector& g) const {
  Vector out(size());
  for (Index k = 0; k < size(); ++k) out(k) = scale_(index_[k]) * g(index_[k]);
  return out;
}

Matrix FreeSubspace::columns(const Matrix& j) const {
  Matrix out(j.rows(), size());
  for (Index k = 0; k < size(); ++k) out.col(k) = scale_(index_[k]) * j.col(index_[k]);
  return out;
}

Matrix FreeSubspace::square(const Matrix& a) const {
  Matrix out(size(), size());
  for (Index c = 0; c < size(); ++c) {
    for (Index r = 0; r < size(); ++r) {
      out(r, c) = scale_(index_[r]) * a(index_[r], index_[c]) * scale_(index_[c]);
    }
  }
  return out;
}

Vector FreeSubspace::step(const Vector& dz) const {
  Vector dx = Vector::Zero(x_.size());
  for (Index k = 0; k < size(); ++k) dx(index_[k]) = scale_(index_[k]) * dz(k);
  return domain_.feasible_step(x_, dx);
}

}  // namespace physgrad
