#include "physgrad/optim/registry.hpp"

#include <algorithm>

#include "physgrad/error.hpp"
#include "physgrad/optim/adam.hpp"
#include "physgrad/optim/bfgs.hpp"
#include "physgrad/optim/gauss_newton.hpp"
#include "physgrad/optim/gradient_descent.hpp"
#include "physgrad/optim/inverse_gradient.hpp"
#include "physgrad/optim/lbfgs.hpp"
#include "physgrad/optim/levenberg_marquardt.hpp"
#include "physgrad/optim/momentum.hpp"
#include "physgrad/optim/newton.hpp"
#include "physgrad/optim/physical_gradient.hpp"

namespace physgrad {

namespace {
struct Entry {
  const char* id;
  const char* label;
  const char* description;
};
constexpr Entry kEntries[] = {
    {"gd", "GD", "gradient descent: Δx = −η ∂L/∂x"},
    {"momentum", "Momentum", "heavy-ball momentum: v ← βv + ∂L/∂x, Δx = −η v"},
    {"adam", "Adam", "Adam: Δx = −η m̂/(√v̂ + ε)"},
    {"newton", "Newton", "Newton, exact Hessian: Δx = −η H⁻¹ ∂L/∂x"},
    {"bfgs", "BFGS", "BFGS with a strong-Wolfe line search: Δx = −α B⁻¹ ∂L/∂x"},
    {"lbfgs", "L-BFGS", "L-BFGS (10 pairs) with a strong-Wolfe line search"},
    {"gn", "Gauss-Newton", "Gauss-Newton: Δx = −η (JᵀH_yJ)⁺ Jᵀ ∂L/∂y"},
    {"lm", "Levenberg-Marquardt", "Levenberg-Marquardt: Δx = −(A + μ diag A)⁻¹ Jᵀ ∂L/∂y, μ by gain ratio"},
    {"ig", "IG", "inverse gradient: Δx = J⁺ Δy, Δy = η (y* − y)"},
    {"pg", "PG", "physical gradient: Δx = P⁻¹(y + Δy; x) − x, Δy = η (y* − y)"},
};

template <typename Rule>
std::unique_ptr<Optimizer> with_lr(const OptimizerSettings& settings) {
  typename Rule::Options options;
  if (settings.lr) options.lr = *settings.lr;
  return std::make_unique<Rule>(options);
}

template <typename Rule>
std::unique_ptr<Optimizer> with_initial_step(const OptimizerSettings& settings) {
  typename Rule::Options options;
  if (settings.lr) options.initial_step = *settings.lr;
  return std::make_unique<Rule>(options);
}
}  // namespace

const std::vector<std::string>& direct_optimizer_ids() {
  static const std::vector<std::string> ids = [] {
    std::vector<std::string> out;
    for (const Entry& entry : kEntries) out.emplace_back(entry.id);
    return out;
  }();
  return ids;
}

std::string describe_optimizer(const std::string& id) {
  for (const Entry& entry : kEntries) {
    if (id == entry.id) return entry.description;
  }
  return {};
}

std::string optimizer_label(const std::string& id) {
  for (const Entry& entry : kEntries) {
    if (id == entry.id) return entry.label;
  }
  return id;
}

std::unique_ptr<Optimizer> make_optimizer(const std::string& id,
                                          const OptimizerSettings& settings) {
  if (id == "gd") return with_lr<GradientDescent>(settings);
  if (id == "momentum") return with_lr<Momentum>(settings);
  if (id == "adam") return with_lr<Adam>(settings);
  if (id == "newton") return with_lr<Newton>(settings);
  if (id == "gn") return with_lr<GaussNewton>(settings);
  if (id == "ig") return with_lr<InverseGradient>(settings);
  if (id == "bfgs") return with_initial_step<Bfgs>(settings);
  if (id == "lbfgs") return with_initial_step<Lbfgs>(settings);
  if (id == "lm") return std::make_unique<LevenbergMarquardt>();
  if (id == "pg") {
    PhysicalGradient::Options options;
    if (settings.lr) options.lr = *settings.lr;
    options.inverse.method = settings.inverse;
    return std::make_unique<PhysicalGradient>(options);
  }
  std::string known;
  for (const std::string& name : direct_optimizer_ids()) known += (known.empty() ? "" : ", ") + name;
  throw Error("unknown optimizer '" + id + "' (known: " + known + ")");
}

}  // namespace physgrad
