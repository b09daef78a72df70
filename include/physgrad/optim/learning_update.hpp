// LearningUpdate — one update rule for training network weights θ through a simulator:
// given what it declares it needs for a mini-batch (∇θ, or the stacked Jacobian), it returns Δθ.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "physgrad/linalg/power_pinv.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/optim/adam.hpp"
#include "physgrad/optim/local_inverse.hpp"
#include "physgrad/optim/stacked_jacobian.hpp"

namespace physgrad {

enum class UpdateNeed {
  kGradient,         // ∇θ of the batch-mean loss
  kStackedJacobian,  // J = ∂(y₁…y_B)/∂θ stacked over samples and outputs, and ∂(mean L)/∂y
  kNetworkOutputs,   // x = f(in; θ), y = P(x), the batch's targets and context, and a backprop
                     // that maps a cotangent at x to ∇θ (for updates that build their own
                     // loss in x, such as SIP)
};

// What the trainer computed for one mini-batch; only the fields the update needs are filled.
// J and ∂L/∂y share one row order (output-major: row k·B + i for sample i, output k); any
// consistent order gives the same J^{−κ}g.
struct BatchState {
  Index batch_size = 0;
  double loss = 0;          // mean per-sample loss over the batch
  Vector gradient;          // ∇θ (mean loss)                          [kGradient]
  std::shared_ptr<const StackedJacobian> jacobian;  // B·m × |θ|, row k·B + i [kStackedJacobian]
  Vector loss_gradient_y;   // B·m, entry k·B + i = ∂(mean L)/∂y_ik    [kStackedJacobian]
  // [kNetworkOutputs]
  const Simulator* physics = nullptr;
  const Loss* loss_function = nullptr;
  Matrix x, y, targets, context;           // one sample per column
  std::function<Vector(const Matrix&)> backprop;  // cotangent at x (n × B) ↦ ∇θ
};

struct UpdateStep {
  Vector delta;                   // Δθ
  double inversion_seconds = 0;   // time spent in the (pseudo-)inversion, if any
  double jacobian_seconds = 0;    // time spent forming J or J Jᵀ, if any
};

class LearningUpdate {
 public:
  virtual ~LearningUpdate() = default;
  virtual std::string id() const = 0;  // sgd, adam, gn, hig, sip
  virtual nlohmann::json params() const = 0;
  virtual UpdateNeed need() const = 0;
  virtual void reset() {}
  virtual UpdateStep step(const BatchState& batch) = 0;
  // The state carried between steps (null for stateless rules), and its restoration for a
  // network with `parameter_count` weights; throws Error on a malformed state.
  virtual nlohmann::json state() const { return nullptr; }
  virtual void restore(const nlohmann::json& /*state*/, Index /*parameter_count*/) {}
  // True when a step may be scaled down after the fact without changing the rule's state, so a
  // step that leads to a non-finite batch can be retried at half its length (gn, hig).
  virtual bool steps_can_be_halved() const { return false; }
};

// Stochastic gradient descent: Δθ = −η ∇θ.
class SgdUpdate final : public LearningUpdate {
 public:
  explicit SgdUpdate(double lr);
  std::string id() const override { return "sgd"; }
  nlohmann::json params() const override { return {{"lr", lr_}}; }
  UpdateNeed need() const override { return UpdateNeed::kGradient; }
  UpdateStep step(const BatchState& batch) override;

 private:
  double lr_;
};

// Adam on ∇θ (AdamState, the same moments as the direct-optimization rule).
class AdamUpdate final : public LearningUpdate {
 public:
  explicit AdamUpdate(AdamOptions options);
  std::string id() const override { return "adam"; }
  nlohmann::json params() const override;
  UpdateNeed need() const override { return UpdateNeed::kGradient; }
  void reset() override { state_.reset(); }
  UpdateStep step(const BatchState& batch) override { return {state_.update(batch.gradient), 0}; }
  nlohmann::json state() const override { return state_.state(); }
  void restore(const nlohmann::json& state, Index parameter_count) override {
    state_.restore(state, parameter_count);
  }

 private:
  AdamState state_;
};

// Δθ = −η J^{−κ} ∂(mean L)/∂y with the truncated power-pseudo-inverse of the stacked Jacobian:
// κ = 1 is Gauss-Newton ("gn"), κ = ½ the half-inverse gradient ("hig"). On the Gram path
// (kAuto with B·m ≤ |θ| and rcond ≥ kMinGramRcond, or kGram) J Jᵀ is built from the network's
// layer factors and J is never formed; otherwise J is formed and passed to power_pinv_apply.
// A non-finite J or J Jᵀ gives a non-finite Δθ, which the trainer rejects.
class JacobianInverseUpdate final : public LearningUpdate {
 public:
  JacobianInverseUpdate(std::string id, double lr, PowerPinvOptions pinv);
  std::string id() const override { return id_; }
  nlohmann::json params() const override;
  UpdateNeed need() const override { return UpdateNeed::kStackedJacobian; }
  UpdateStep step(const BatchState& batch) override;
  bool steps_can_be_halved() const override { return true; }
  // Backend and kept rank of the last step.
  const PowerPinvInfo& last_info() const { return info_; }
  double lr() const { return lr_; }
  const PowerPinvOptions& pinv_options() const { return pinv_; }

 private:
  std::string id_;
  double lr_;
  PowerPinvOptions pinv_;
  PowerPinvInfo info_{};
};

// Scale-invariant physics (SIP) training: per sample, x̃ᵢ = P⁻¹(yᵢ + η Δyᵢ; xᵢ) with Δy the
// Newton step of the loss in y (y* − y for L2), then Adam on the proxy loss mean ½‖xᵢ − x̃ᵢ‖²
// with x̃ held constant, i.e. on the cotangent (xᵢ − x̃ᵢ)/B backpropagated through the network.
struct SipOptions {
  AdamOptions adam;     // the first-order rule on the proxy loss (lr = η_NN)
  double y_step = 1.0;  // η > 0: fraction of the Newton step in y
  LocalInverseOptions inverse;  // the simulator's own inverse when it has one (auto)
};

class SipUpdate final : public LearningUpdate {
 public:
  explicit SipUpdate(SipOptions options);
  std::string id() const override { return "sip"; }
  nlohmann::json params() const override;
  UpdateNeed need() const override { return UpdateNeed::kNetworkOutputs; }
  void reset() override { adam_.reset(); }
  UpdateStep step(const BatchState& batch) override;
  nlohmann::json state() const override { return adam_.state(); }
  void restore(const nlohmann::json& state, Index parameter_count) override {
    adam_.restore(state, parameter_count);
  }

 private:
  SipOptions options_;
  AdamState adam_;
};

// Learning-rule ids, in display order: sgd, adam, gn, hig, sip.
const std::vector<std::string>& learning_update_ids();

struct LearningUpdateSettings {
  std::optional<double> lr = std::nullopt;     // default: sgd 1e-2, adam and sip 1e-3, gn/hig 1
  std::optional<double> rcond = std::nullopt;  // truncation τ of gn/hig (default 1e-6)
  PinvBackend backend = PinvBackend::kAuto;
  double sip_y_step = 1.0;                     // η of sip
  InverseMethod inverse = InverseMethod::kAuto;  // local inverse of sip
};

// Throws Error naming an unknown id (and the known ones) or an out-of-range setting.
std::unique_ptr<LearningUpdate> make_learning_update(const std::string& id,
                                                     const LearningUpdateSettings& settings = {});

}  // namespace physgrad
