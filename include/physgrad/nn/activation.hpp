// Activation — the element-wise nonlinearities σ(z) of a dense layer and their derivatives σ'(z):
// tanh, relu max(z, 0), sigmoid 1/(1 + e^−z), softplus log(1 + e^z), identity z.
#pragma once

#include <string>

#include "physgrad/types.hpp"

namespace physgrad {

enum class Activation { kTanh, kRelu, kSigmoid, kSoftplus, kIdentity };

// "tanh", "relu", "sigmoid", "softplus", "identity".
std::string to_string(Activation activation);
// Inverse of to_string; throws Error listing the known names for anything else.
Activation parse_activation(const std::string& text);

// out = σ(z) element-wise. out must have z's shape and may be z itself.
void apply(Activation activation, const Eigen::Ref<const Eigen::ArrayXXd>& z,
           Eigen::Ref<Eigen::ArrayXXd> out);

// out = σ'(z) element-wise (relu: 0 at z = 0). out must have z's shape and may be z itself.
void derivative(Activation activation, const Eigen::Ref<const Eigen::ArrayXXd>& z,
                Eigen::Ref<Eigen::ArrayXXd> out);

// Both at once: z is replaced by σ(z) and slope receives σ'(z), the same values as apply() and
// derivative(), but tanh and relu take σ' from σ (1 − σ², σ > 0) instead of evaluating twice.
void apply_with_derivative(Activation activation, Eigen::Ref<Eigen::ArrayXXd> z,
                           Eigen::Ref<Eigen::ArrayXXd> slope);

}  // namespace physgrad
