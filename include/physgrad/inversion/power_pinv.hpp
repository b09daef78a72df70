// Truncated power-pseudo-inverse applied to a vector: J^{−κ} g = V diag(σᵢ^{−κ}) Uᵀ g over the
// singular values σᵢ > rcond·σ_max of J = U Σ Vᵀ; the others contribute nothing (κ = 1: J⁺ g).
#pragma once

#include <string>

#include "physgrad/inversion/jacobian_operator.hpp"
#include "physgrad/spectral_cut.hpp"
#include "physgrad/types.hpp"

namespace physgrad {

// How J^{−κ} g is computed (r = rows, c = cols of J). The SVD is accurate to ~ε·σ_max/σ_min,kept
// relative; the Gram and normal paths square the spectrum, so theirs is ~ε·(σ_max/σ_min,kept)²
// and they resolve σ only down to ~√ε·σ_max.
//   kSvd:    thin SVD of J (LAPACK dgesdd), O(r·c·min(r, c)); any rcond.
//   kGram:   G = J Jᵀ = U Σ² Uᵀ (dsyrk + an eigensolve), result Jᵀ U Σ^{−1−κ} Uᵀ g;
//            O(r²·c + r³) — the fast choice for wide J (r ≤ c).
//   kNormal: A = Jᵀ J = V Σ² Vᵀ, result V Σ^{−1−κ} Vᵀ (Jᵀ g); O(c²·r + c³) — for tall J.
//   kAuto:   kGram when r ≤ c, kNormal otherwise; kSvd when rcond < kMinGramRcond.
enum class PinvBackend { kAuto, kSvd, kGram, kNormal };

std::string to_string(PinvBackend backend);  // "auto", "svd", "gram", "normal"
// Throws unknown_name_error (text.hpp) on an unknown name.
PinvBackend parse_pinv_backend(const std::string& name);

// Smallest relative cutoff the Gram and normal paths use. Forming Σ² and its eigensolve leave
// an absolute error of a few ε·σ_max² on every eigenvalue σᵢ², so σᵢ below √ε·σ_max ≈ 1.5e-8·σ_max
// are noise; at 1e-7 the smallest kept σᵢ² is ~45 ε·σ_max², clear of that noise (a result made
// mostly of directions near this floor can still be off by ~1–20 %). A smaller rcond is raised to
// this value there, and makes kAuto choose the SVD.
inline constexpr double kMinGramRcond = 1e-7;

// The arithmetic of the eigensolve on the Gram and normal paths (the SVD is always double).
//   kDouble: the symmetric matrix W = J Jᵀ or JᵀJ as formed (LAPACK dsytrd, dsyevd, dsyevr).
//   kFloat:  W rounded to float (ssytrd, ssyevd, ssyevr): about twice as fast, but every eigenvalue
//            λᵢ = σᵢ² carries an error of up to δ = √n·ε_f·λ_max (ε_f = 2⁻²³ ≈ 1.2e-7).
//   kAuto:   float where the spectrum allows it (float_resolves_spectrum() on the float
//            eigenvalues; the result is then within ~(1+κ)/kFloatAccuracy relative of the double
//            one), else double; with `previous` set, float is tried only when the previous
//            spectrum allowed it, so that a spectrum that does not costs no float attempt.
enum class PinvPrecision { kAuto, kDouble, kFloat };
std::string to_string(PinvPrecision precision);  // "auto", "double", "float"
PinvPrecision parse_pinv_precision(const std::string& name);

// How the Gram and normal paths solve the eigenproblem of the n × n W.
//   kTridiagonal: W = Q T Qᵀ (sytrd), every eigenvalue of T by the implicit QL iteration with
//            its rotations S kept (tridiagonal_eigen.hpp), result Q S f(Λ) Sᵀ Qᵀ x: no
//            eigenvector is formed, O(n²) beyond the reduction's 4n³/3.
//   kFull:   all n eigenpairs (syevd, divide and conquer), result from the eigenvectors.
//   kSubset: only λ above the cut (syevr by value range, from a lower bound of λ_max by power
//            iteration): saves the back-transformation of the dropped directions.
//   kAuto:   kSubset when `previous` kept at most kSubsetKeptFraction of n directions, else
//            kTridiagonal.
enum class PinvEigensolver { kAuto, kFull, kSubset, kTridiagonal };
std::string to_string(PinvEigensolver eigensolver);  // "auto", "full", "subset", "tridiagonal"
PinvEigensolver parse_pinv_eigensolver(const std::string& name);

// Float is accepted when every kept eigenvalue is at least this many times its error δ (so its
// relative error is ≤ 1e-3) and no eigenvalue lies within δ of the cut.
inline constexpr double kFloatAccuracy = 1e3;
// kAuto picks the subset eigensolver at or below this kept fraction (bench/learning_step_bench.cpp,
// eigen_route: at 7.6 % kept dsyevr ties the tridiagonal eigensolver, above it loses).
inline constexpr double kSubsetKeptFraction = 0.1;

struct PowerPinvInfo;

struct PowerPinvOptions {
  // κ: 1 = pseudo-inverse (Gauss-Newton, IG), 0.5 = HIG, −1 = Jᵀ; keep σᵢ > rcond·σ_max
  // (strictly), 0 ≤ rcond < 1. No damping (Error otherwise); the path sets the floor (pinv_cut).
  SpectralCut cut{};
  PinvBackend backend = PinvBackend::kAuto;
  PinvPrecision precision = PinvPrecision::kDouble;
  PinvEigensolver eigensolver = PinvEigensolver::kAuto;
  // What the previous call on a matrix like this one did (the last step of the same rule): the
  // auto choices above follow it; nullptr: no history.
  const PowerPinvInfo* previous = nullptr;
};

// What a call did.
struct PowerPinvInfo {
  PinvBackend backend = PinvBackend::kAuto;  // the path taken (never kAuto after a call)
  Index rank = 0;                            // number of kept singular values
  double sigma_max = 0;                      // largest singular value of J
  double sigma_min_kept = 0;                 // smallest kept one (0 when none is kept)
  double rcond_used = 0;                     // the cutoff applied (rcond, or the Gram floor)
  // The eigensolve that gave the result (Gram and normal paths; the SVD reports double, full).
  PinvPrecision precision = PinvPrecision::kDouble;
  PinvEigensolver eigensolver = PinvEigensolver::kFull;
  bool float_rejected = false;  // kAuto solved in float first; the spectrum sent it to double
  bool float_resolves = false;  // this spectrum passes the float check (next kAuto tries float)
};

// σ_max / σ_min,kept, the condition number of the kept part of J (0 when nothing is kept).
double kept_condition(const PowerPinvInfo& info);

// The float check: with δ = √n·ε_f·λ_max, every eigenvalue λᵢ of the n × n matrix is either
// kept clearly and accurately, λᵢ ≥ max(kFloatAccuracy·δ, cut² + δ), or dropped clearly,
// λᵢ ≤ cut² − δ (cut² = `cut`.lambda_cut(λ_max) = τ²·λ_max). Eigenvalues within δ of these true
// values then keep the same directions, each λ to 1/kFloatAccuracy relative.
bool float_resolves_spectrum(const Vector& lambda, Index n, const SpectralCut& cut);

// Where the time of a call went.
struct PowerPinvTiming {
  double forming_seconds = 0;    // J Jᵀ, J, or Jᵀ J (and Jᵀg) from the operator
  double inversion_seconds = 0;  // the factorization and the products around it
};

// The cut of the path `backend` (spectral_cut.hpp): `options.cut`, its floor raised to
// kMinGramRcond on the Gram and normal paths.
SpectralCut pinv_cut(PinvBackend backend, const PowerPinvOptions& options);

// The path `options.backend` stands for on an r × c matrix: kAuto resolved as described above.
PinvBackend resolve_pinv_backend(Index rows, Index cols, const PowerPinvOptions& options);

// J^{−κ} g for g of J.rows() entries, on the path resolve_pinv_backend() picks: the Gram path
// from J.gram() and J.apply_transpose(), the normal path from J.normal(g), the SVD of
// J.materialize(). An empty J gives the zero vector of J.cols() entries. Throws Error on
// mismatched sizes, rcond outside [0, 1), non-finite κ or a damping; NumericalError on
// non-finite entries of g or of what the operator forms, or a LAPACK routine that fails.
Vector power_pinv_apply(const JacobianOperator& j, const Vector& g,
                        const PowerPinvOptions& options = {}, PowerPinvInfo* info = nullptr,
                        PowerPinvTiming* timing = nullptr);

// The same for a formed matrix (DenseJacobian), which must be finite (NumericalError otherwise).
Vector power_pinv_apply(const Matrix& j, const Vector& g, const PowerPinvOptions& options = {},
                        PowerPinvInfo* info = nullptr);

// Truncated pseudo-inverse of a symmetric matrix applied to g (the normal-equation solve of
// Gauss-Newton, Newton's Hessian solve): A⁺ g over the eigenvalues |λᵢ| > τ²·|λ|max, i.e. the
// cut's τ on σ = √|λ| as everywhere (cut_symmetric in spectral_cut.hpp, which also applies a κ
// other than 1 and a damping; the direct rules give only τ).
Vector symmetric_pinv_apply(const Matrix& a, const Vector& g, const SpectralCut& cut);

}  // namespace physgrad
