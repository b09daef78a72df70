// KroneckerHigUpdate — the κ-family with Kronecker-factored curvature: per dense layer JᵀJ ≈ A ⊗ S,
// Δ[W b] = −η S^{−p} ∇[W b] A^{−p}, p = (1+κ)/2 (κ = 1: K-FAC; κ = ½: HIG's (JᵀJ)^{−3/4}).
#pragma once

#include <random>
#include <vector>

#include "physgrad/learn/learning_update.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"
#include "physgrad/spectral_cut.hpp"

namespace physgrad {

// The block of JᵀJ of a dense layer z = W a + b is Σ_{i,k} (ā_i ā_iᵀ) ⊗ (δ_ik δ_ikᵀ) (ā = [a; 1],
// δ_ik the layer's output cotangent of row k·B + i of J); K-FAC's approximation is A ⊗ S with
// A = (1/B) Σ_i ā_i ā_iᵀ and S = Σ_{i,k} δ_ik δ_ikᵀ — exact when δ_ik does not depend on the
// sample (a single dense layer with identity physics: S = B·I). A convolution counts its P output
// positions as extra samples (KFC): A = (1/B) Σ_{i,p} ā_ip ā_ipᵀ over its input patches,
// S = (1/P) Σ_{i,k,p} δ_ikp δ_ikpᵀ (nn/network.hpp), the dense layer's for P = 1. Then (A ⊗ S)^{−p} vec(G) =
// vec(S^{−p} G A^{−p}), each factor taking the whole exponent p = (1+κ)/2 of the exact step
// Δθ = −η (JᵀJ)^{−p} ∇θL, and every layer is updated on its own (blocks between layers dropped).
// Each factor's eigenvalues λ ≤ τ²λ_max are dropped (τ as HIG's cut on σ) and the others damped,
// f(λ) = (λ + damping·λ_max)^{−p}. The factors are refreshed every `refresh` steps,
// F ← factor_decay·F + (1 − decay)·F_batch (the first refresh takes F_batch), and their powers reused
// in between, where the rule needs only ∇θL (need() is then kGradient: no Jacobian is formed).
// Cost of a refresh: one backward sweep of the B·m output cotangents (as for J Jᵀ), the factor
// products Σ w_l²·B·m, and one eigendecomposition per factor (O(w_l³)); of every step: ∇θL and
// two products per layer, O(Σ w_out·w_in·(w_out + w_in)).
// With `samples` K > 0 a refresh draws, per sample i, K orthonormal directions Q_i ∈ R^{m×K}
// (the Q of a Gaussian matrix's QR: E[Q_i Q_iᵀ] = (K/m)·I) and S sums δ δᵀ over the layer's
// cotangents of the K rows √(m/K)·(Q_i e_j)ᵀ J_i instead of the m rows of J_i: E[S] is the exact
// S, and S is exact when K = m (Q_i Q_iᵀ = I). Cost: K physics VJPs and K backward sweeps instead
// of m. The directions come from the rule's own generator (seeded at reset, saved with the state).
struct KroneckerHigOptions {
  double lr = 1.0;         // η > 0
  // κ ½: id "kfac-hig", 1: K-FAC, id "kfac"; the relative cut τ in [0, 1) (factor eigenvalues
  // λ ≤ τ²λ_max dropped); the damping ≥ 0 added to every kept factor eigenvalue, times λ_max.
  SpectralCut cut{.kappa = 0.5, .rcond = 1e-6, .damping = 1e-2};
  int refresh = 10;        // steps from one factor refresh to the next, ≥ 1
  double factor_decay = 0.9;      // weight of the old factors in the running average, in [0, 1)
  int samples = 0;         // K output directions per sample at a refresh, ≤ m; 0: all m outputs

  static const OptionList<KroneckerHigOptions>& descriptors();
};

class KroneckerHigUpdate final : public LearningUpdate {
 public:
  using Options = KroneckerHigOptions;
  // Its rules in the catalogue, one per id it is built as, each with its defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "kfac", .label = "K-FAC",
         .formula = "Δ[W b] = −η S⁻¹ ∇[W b] A⁻¹ per dense layer, JᵀJ ≈ A ⊗ S (running averages)",
         .colour = "#9e6b3b", .defaults = {.cut = KroneckerHigOptions{}.cut.with_kappa(1.0)},
         .derivative = RuleDerivative::kJacobianProducts, .settings_from = "gn"},
        {.id = "kfac-hig", .label = "Kronecker HIG",
         .formula = "Δ[W b] = −η S^{−3/4} ∇[W b] A^{−3/4} per dense layer, JᵀJ ≈ A ⊗ S (running averages)",
         .colour = "#66c2a4",
         .derivative = RuleDerivative::kJacobianProducts, .settings_from = "hig"},
    };
    return list;
  }
  // Built as `id`, one of rules(): it reports that id whatever κ is (kfac with κ = ½
  // is still kfac); without one, the id of its κ (κ = 1: kfac, else kfac-hig). Throws Error
  // naming another id.
  explicit KroneckerHigUpdate(Options options = {}, const std::string& id = {});
  std::string id() const override { return id_; }
  nlohmann::json params() const override;
  // The stacked Jacobian on the steps that refresh the factors (with samples: the gradient and
  // weighted factors), else the gradient.
  UpdateNeed need() const override;
  Step step(const BatchState& batch) override;
  double learning_rate() const override { return options_.lr; }
  void set_learning_rate(double lr) override;
  bool steps_can_be_halved() const override { return true; }
  void reset() override;
  // The step count, the running-average factors of every layer and (with samples) the
  // generator's state; the powers are recomputed from them, so a resumed run continues with the
  // same bits.
  nlohmann::json state() const override;
  void restore(const nlohmann::json& state, Index parameter_count) override;

  // One layer's running factors A, S and where its weights lie in θ ([vec(W), b], or
  // [vec(Wᵀ), b] when transposed, as DenseLayerFactors).
  struct Layer {
    Index offset = 0, outputs = 0, inputs = 0;
    bool transposed = false;
    Matrix input_factor, cotangent_factor;  // A, S
  };

 private:
  // The steps of step(): ∇θL of the batch (given, or Jᵀ ∂L/∂y); the layers with the batch's
  // factors averaged in (one layer: average_factors); that they hold every parameter; the
  // refreshed layers made current with their powers (nothing changes when this throws); the
  // step −η S^{−p} ∇[W b] A^{−p} of every layer.
  Vector parameter_gradient(const BatchState& batch) const;
  void average_factors(Layer& layer, const DenseLayerFactors& f, double weight, double batch_size,
                       std::size_t l) const;
  std::vector<Layer> refreshed_layers(const std::vector<DenseLayerFactors>& factors,
                                      double batch_size) const;
  // The batch's factors over K = samples random directions per sample (weights √(m/K)·Q_i),
  // drawn with `rng` (a copy of the rule's, installed by step() once nothing can throw).
  std::vector<DenseLayerFactors> sampled_factors(const BatchState& batch,
                                                 std::mt19937_64& rng) const;
  void check_covers(const std::vector<Layer>& layers, Index parameters) const;
  void install(std::vector<Layer>& refreshed, bool refreshing);
  Vector preconditioned_step(const Vector& gradient) const;
  void refresh_powers();

  Options options_;
  std::string id_;  // the catalogue id it was built as
  long long steps_ = 0;  // steps made since the last reset
  std::vector<Layer> layers_;
  std::mt19937_64 rng_;  // draws the output directions (samples > 0)
  // S^{−p} and A^{−p} of each layer (empty: to be computed from layers_).
  std::vector<Matrix> input_powers_, cotangent_powers_;
};

}  // namespace physgrad
