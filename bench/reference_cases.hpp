// Reference cases of the benchmarks — the experiments' configurations a benchmark's range(0)
// names (experiment, batch B; J is B·m × |θ|), and the eigensolve modes of the HIG Gram path.
#pragma once

#include <cstddef>
#include <cstdint>

#include "physgrad/inversion/power_pinv.hpp"
#include "registry.hpp"

namespace physgrad::bench {

using run::ReferenceCase;

// The reference configurations: the experiment and the batch size.
struct CaseSpec {
  const char* experiment;
  Index batch;
  const char* label;
};

inline constexpr CaseSpec kCases[] = {
    {"hig-toy", 128, "hig_toy"},              // 0: J 256 × 30
    {"oscillators", 128, "oscillators"},      // 1: J 512 × 2956
    {"poisson", 16, "poisson"},               // 2: J 1024 × 24 896
    {"poisson", 64, "poisson_b64"},           // 3: J 4096 × 24 896 (the HIG paper's batch)
    {"quantum-dipole", 16, "quantum_dipole"},  // 4: J 448 × 9484
};

inline const CaseSpec& case_spec(std::int64_t which) { return kCases[static_cast<std::size_t>(which)]; }

inline ReferenceCase make_case(std::int64_t which, Index batch = 0) {
  const CaseSpec& spec = case_spec(which);
  return experiments::builtin_registry().reference(spec.experiment, batch > 0 ? batch : spec.batch);
}

inline const char* rule_id(std::int64_t rule) {
  static const char* const ids[] = {"adam", "gn", "hig", "sip"};
  return ids[rule];
}

// The eigensolve modes the benchmarks compare, by index: 0 dsyevd (all pairs), 1 dsyevr (pairs
// above the cutoff), 2 ssyevd, 3 ssyevr (the same in float), 4 auto precision and eigensolver,
// 5 dsytrd + QL rotations applied to the vector (the tridiagonal eigensolver), 6 ssytrd + QL.
struct EigensolveMode {
  PinvPrecision precision;
  PinvEigensolver eigensolver;
  const char* label;
};
inline constexpr EigensolveMode kEigensolveModes[] = {
    {PinvPrecision::kDouble, PinvEigensolver::kFull, "dsyevd"},
    {PinvPrecision::kDouble, PinvEigensolver::kSubset, "dsyevr above cutoff"},
    {PinvPrecision::kFloat, PinvEigensolver::kFull, "ssyevd"},
    {PinvPrecision::kFloat, PinvEigensolver::kSubset, "ssyevr above cutoff"},
    {PinvPrecision::kAuto, PinvEigensolver::kAuto, "auto"},
    {PinvPrecision::kDouble, PinvEigensolver::kTridiagonal, "dsytrd + QL"},
    {PinvPrecision::kFloat, PinvEigensolver::kTridiagonal, "ssytrd + QL"},
};

inline PowerPinvOptions eigensolve_options(std::int64_t mode, double kappa, double rcond) {
  const EigensolveMode& m = kEigensolveModes[mode];
  return {.cut = {.kappa = kappa, .rcond = rcond},
          .precision = m.precision,
          .eigensolver = m.eigensolver};
}

inline const char* eigensolve_label(std::int64_t mode) { return kEigensolveModes[mode].label; }

}  // namespace physgrad::bench
