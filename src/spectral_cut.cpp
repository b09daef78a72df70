#include "physgrad/spectral_cut.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

void require_in_range(bool ok, std::string_view who, const char* what, const char* range,
                      double value) {
  if (ok) return;
  std::ostringstream msg;
  msg << who << ": " << what << " must be " << range << ", got " << value;
  throw Error(msg.str());
}

void require_finite_spectrum(const Vector& values, const char* what) {
  if (!all_finite(values)) {
    throw NumericalError(std::string("spectral cut: non-finite ") + what + " in the spectrum");
  }
}

// The kept count, σ_max and the smallest kept σ of `sigma` (≥ 0) under `cut`; weights from
// weight(i) for the kept entries.
template <class Weight>
CutSpectrum cut_sigmas(const SpectralCut& cut, const Vector& sigma, const Weight& weight) {
  CutSpectrum out;
  out.weights = Vector::Zero(sigma.size());
  out.sigma_max = sigma.size() > 0 ? sigma.maxCoeff() : 0.0;
  for (Index i = 0; i < sigma.size(); ++i) {
    if (!cut.keeps(sigma(i), out.sigma_max)) continue;
    out.weights(i) = weight(i);
    out.sigma_min_kept = out.kept == 0 ? sigma(i) : std::min(out.sigma_min_kept, sigma(i));
    ++out.kept;
  }
  return out;
}

}  // namespace

void SpectralCut::check(std::string_view who) const {
  require_in_range(std::isfinite(kappa), who, "kappa", "finite", kappa);
  require_in_range(rcond >= 0 && rcond < 1, who, "rcond", "in [0, 1)", rcond);
  require_in_range(damping >= 0 && std::isfinite(damping), who, "damping", "≥ 0 and finite",
                   damping);
  require_in_range(floor >= 0 && floor < 1, who, "the rcond floor", "in [0, 1)", floor);
}

double SpectralCut::cutoff() const { return std::max(rcond, floor); }

bool SpectralCut::keeps(double sigma, double sigma_max) const {
  return sigma > cutoff() * sigma_max;
}

double SpectralCut::lambda_cut(double lambda_max) const {
  const double tau = cutoff();
  return tau * tau * lambda_max;
}

double SpectralCut::lambda_weight(double lambda, double lambda_max) const {
  return std::pow(std::sqrt(std::max(lambda, 0.0) + damping * lambda_max), -1 - kappa);
}

double CutSpectrum::condition() const {
  return kept > 0 && sigma_min_kept > 0 ? sigma_max / sigma_min_kept : 0.0;
}

CutSpectrum cut_singular_values(const SpectralCut& cut, const Vector& sigma) {
  require_finite_spectrum(sigma, "singular value");
  CutSpectrum out = cut_sigmas(cut, sigma, [](Index) { return 1.0; });
  // The kept σ gathered in order, raised to −κ together, put back.
  Vector kept(out.kept);
  for (Index i = 0, k = 0; i < sigma.size(); ++i) {
    if (out.weights(i) != 0) kept(k++) = sigma(i);
  }
  kept = kept.array().pow(-cut.kappa).matrix();
  for (Index i = 0, k = 0; i < sigma.size(); ++i) {
    if (out.weights(i) != 0) out.weights(i) = kept(k++);
  }
  return out;
}

CutSpectrum cut_squared(const SpectralCut& cut, const Vector& lambda) {
  require_finite_spectrum(lambda, "eigenvalue");
  const Vector sigma = lambda.cwiseMax(0.0).cwiseSqrt();
  const double lambda_max = lambda.size() > 0 ? std::max(lambda.maxCoeff(), 0.0) : 0.0;
  return cut_sigmas(cut, sigma,
                    [&](Index i) { return cut.lambda_weight(lambda(i), lambda_max); });
}

CutSpectrum cut_symmetric(const SpectralCut& cut, const Vector& lambda, Vector& coefficients) {
  if (lambda.size() != coefficients.size()) {
    throw Error("spectral cut: " + std::to_string(lambda.size()) + " eigenvalues but " +
                std::to_string(coefficients.size()) + " coefficients");
  }
  require_finite_spectrum(lambda, "eigenvalue");
  const Vector sigma = lambda.cwiseAbs().cwiseSqrt();
  const double largest = lambda.size() > 0 ? lambda.cwiseAbs().maxCoeff() : 0.0;
  CutSpectrum out = cut_sigmas(cut, sigma, [&](Index i) {
    const double sign = lambda(i) < 0 ? -1.0 : 1.0;
    return sign * cut.lambda_weight(std::abs(lambda(i)), largest);
  });
  for (Index i = 0; i < lambda.size(); ++i) {
    if (out.weights(i) == 0) {
      coefficients(i) = 0.0;
    } else if (cut.kappa == 1.0 && cut.damping == 0.0) {
      coefficients(i) /= lambda(i);  // the correctly rounded quotient, not c·λ^{−1}
    } else {
      coefficients(i) *= out.weights(i);
    }
  }
  return out;
}

const OptionDescription& kappa_option_description() {
  static const OptionDescription description{
      "kappa", any_finite(),
      "exponent κ of J^{−κ} = V Σ^{−κ} Uᵀ, i.e. (J Jᵀ)^{−(1+κ)/2} on the squared spectrum: "
      "½ HIG, 1 Gauss-Newton / K-FAC"};
  return description;
}

const OptionDescription& rcond_option_description() {
  static const OptionDescription description{
      "rcond", fraction(),
      "relative cut τ on singular values σ of J, with λ = σ² for a curvature (JᵀJ, J Jᵀ, a "
      "Kronecker factor, the Hessian's |λ|): directions with σ ≤ τ·σ_max (λ ≤ τ²λ_max) are "
      "dropped",
      {},
      OptionGroup::kInversion};
  return description;
}

const OptionDescription& damping_option_description() {
  static const OptionDescription description{
      "damping", non_negative(),
      "added to every kept eigenvalue λ = σ², relative to the largest (λ + damping·λ_max)", {},
      OptionGroup::kInversion};
  return description;
}

}  // namespace physgrad
