// Spectral cut — the one truncated power of a spectrum: keep the directions whose singular value
// σ > τ·σ_max (τ = max(rcond, floor)) and weight them σ^{−κ}, or (λ + d·λ_max)^{−(1+κ)/2} on λ = σ².
#pragma once

#include <string_view>

#include "physgrad/rule_option.hpp"
#include "physgrad/types.hpp"

namespace physgrad {

// rcond means one thing on every path: it is relative to the largest singular value σ_max of the
// matrix J whose (power-)pseudo-inverse a rule applies — the Jacobian of the inverse gradient,
// of Gauss-Newton and of HIG, a Kronecker factor's square root, the Hessian's square root for
// Newton. Where a path holds the squared spectrum λ = σ² (J Jᵀ, JᵀJ, JᵀH_yJ, a Kronecker factor,
// Ritz values, the Hessian with |λ|), the cut is the same σ = √λ > τ·σ_max, i.e. λ > τ²·λ_max.
//   kappa:   the power, J^{−κ} = V Σ^{−κ} Uᵀ; on λ: λ^{−(1+κ)/2} (κ = 1 pseudo-inverse, ½ HIG).
//   rcond:   the relative cut τ on σ, in [0, 1).
//   damping: added to every kept λ, times λ_max (≥ 0; only on λ = σ², K-FAC's damping).
//   floor:   the smallest τ the path resolves (the Gram, normal and Lanczos paths form σ² and
//            use kMinGramRcond, inversion/power_pinv.hpp); rcond below it is raised to it.
struct SpectralCut {
  double kappa = 1.0;
  double rcond = 1e-10;
  double damping = 0.0;
  double floor = 0.0;

  // Error naming the offending value: κ not finite, rcond or floor outside [0, 1), damping < 0
  // or not finite. `who` starts the message.
  void check(std::string_view who) const;
  // The relative cut applied on σ: max(rcond, floor).
  double cutoff() const;
  // Whether a direction of singular value σ stays, σ_max the largest: σ > cutoff()·σ_max (strictly:
  // nothing stays of an all-zero spectrum, a σ exactly on the cut is dropped).
  bool keeps(double sigma, double sigma_max) const;
  // cutoff()²·λ_max: the cut on λ = σ², for bounds on an eigensolve (the float check, the lower
  // end of a subset eigensolve).
  double lambda_cut(double lambda_max) const;
  // The weight of a kept λ = σ² of J Jᵀ or JᵀJ for J^{−κ} through it: σ̃^{−1−κ}, σ̃ = √(λ⁺ + d·λ_max),
  // λ⁺ = max(λ, 0) (rounding can leave λ slightly < 0) — (λ + d·λ_max)^{−(1+κ)/2}.
  double lambda_weight(double lambda, double lambda_max) const;
  // This cut with the power κ = `power` (the defaults of a rule's κ = 1 id: gn is hig's cut at 1).
  constexpr SpectralCut with_kappa(double power) const {
    SpectralCut out = *this;
    out.kappa = power;
    return out;
  }
};

// What the cut kept of one spectrum (the diagnostics rules report: kept count, condition).
struct CutSpectrum {
  Vector weights;             // per entry of the spectrum: its weight, 0 where dropped
  Index kept = 0;             // directions kept
  double sigma_max = 0;       // largest σ of the spectrum
  double sigma_min_kept = 0;  // smallest kept σ (0 when none is kept)
  // σ_max / σ_min,kept, the condition of the kept part (0 when nothing is kept).
  double condition() const;
};

// The cut of singular values σ ≥ 0 (any order): weights σ^{−κ} (J^{−κ} from J's SVD), evaluated
// over the kept σ in their order as one array. NumericalError on a non-finite σ.
CutSpectrum cut_singular_values(const SpectralCut& cut, const Vector& sigma);
// The cut of the eigenvalues λ = σ² of a positive semi-definite J Jᵀ, JᵀJ or Kronecker factor
// (any order): weights lambda_weight(). NumericalError on a non-finite λ.
CutSpectrum cut_squared(const SpectralCut& cut, const Vector& lambda);
// The cut of the eigenvalues λ of a symmetric, possibly indefinite matrix (the Hessian of Newton,
// JᵀH_yJ of Gauss-Newton) read as λ = ±σ²: |λ| > cutoff()²·|λ|max stays. Solves in place: each
// kept coefficient cᵢ becomes cᵢ/λᵢ for κ = 1 (the exact quotient) and sign(λᵢ)·cᵢ·(|λᵢ| +
// d·|λ|max)^{−(1+κ)/2} otherwise; dropped ones become 0. Error on mismatched sizes, NumericalError
// on a non-finite λ.
CutSpectrum cut_symmetric(const SpectralCut& cut, const Vector& lambda, Vector& coefficients);

// The option descriptions of the cut, the same for every rule that has it (name, range, help).
const OptionDescription& kappa_option_description();
const OptionDescription& rcond_option_description();
const OptionDescription& damping_option_description();

// The cut's options as options of a rule's struct `Options` whose SpectralCut member `cut` holds
// them (rcond_option(&HigOptions::cut) is the option "rcond", HigOptions::cut.rcond).
template <class Options>
RuleOption<Options> kappa_option(SpectralCut Options::*cut) {
  return rule_option(kappa_option_description(), cut, &SpectralCut::kappa);
}
template <class Options>
RuleOption<Options> rcond_option(SpectralCut Options::*cut) {
  return rule_option(rcond_option_description(), cut, &SpectralCut::rcond);
}
template <class Options>
RuleOption<Options> damping_option(SpectralCut Options::*cut) {
  return rule_option(damping_option_description(), cut, &SpectralCut::damping);
}
// The relative cut of a rule that has no other part of the cut (the direct Gauss-Newton and
// Newton, the inverse gradient: κ = 1), as its double member.
template <class Options>
RuleOption<Options> rcond_option(double Options::*member) {
  const OptionDescription& description = rcond_option_description();
  return rule_option(description.name, member, description.range, description.help);
}

}  // namespace physgrad
