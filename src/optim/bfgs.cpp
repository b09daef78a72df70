#include "physgrad/optim/bfgs.hpp"

namespace physgrad {

const OptionList<BfgsOptions>& BfgsOptions::descriptors() {
  static const OptionList<BfgsOptions> options = joined<BfgsOptions>({
      {initial_step_option(&BfgsOptions::initial_step)},
      nested_options(&BfgsOptions::line_search),
  });
  return options;
}

Bfgs::Bfgs(Options options)
    : QuasiNewton(checked("bfgs", options).initial_step, options.line_search),
      options_(options) {}

Vector Bfgs::direction(const Vector& gradient) const {
  return updated_ ? Vector(-h_ * gradient) : Vector(-gradient);
}

void Bfgs::clear_curvature() {
  h_.resize(0, 0);
  updated_ = false;
}

void Bfgs::add_pair(const Vector& s, const Vector& y) {
  const double ys = y.dot(s);
  if (!updated_) h_ = (ys / y.squaredNorm()) * Matrix::Identity(s.size(), s.size());
  // (I − ρ s yᵀ) H (I − ρ y sᵀ) + ρ s sᵀ expanded with the symmetric H and Hy = H y:
  // H − ρ (s (Hy)ᵀ + Hy sᵀ) + ρ (1 + ρ yᵀHy) s sᵀ.
  const double rho = 1 / ys;
  const Vector hy = h_ * y;
  h_ -= rho * (s * hy.transpose() + hy * s.transpose());
  h_ += rho * (1 + rho * y.dot(hy)) * s * s.transpose();
  updated_ = true;
}

}  // namespace physgrad
