#include "physgrad/nn/activation.hpp"

#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/text.hpp"

namespace physgrad {

namespace {

constexpr NameTable<Activation, 5> kNames{{
    {Activation::kTanh, "tanh"},
    {Activation::kRelu, "relu"},
    {Activation::kSigmoid, "sigmoid"},
    {Activation::kSoftplus, "softplus"},
    {Activation::kIdentity, "identity"},
}};

// 1/(1 + e^−z) through s = e^−|z| ≤ 1, so neither branch overflows or cancels.
double sigmoid(double z) {
  const double s = std::exp(-std::abs(z));
  return z >= 0 ? 1 / (1 + s) : s / (1 + s);
}

// σ(z)(1 − σ(z)) = s/(1 + s)², s = e^−|z| (the function is even).
double sigmoid_derivative(double z) {
  const double s = std::exp(-std::abs(z));
  return s / ((1 + s) * (1 + s));
}

void check_shape(const char* what, const Eigen::Ref<const Eigen::ArrayXXd>& z,
                 const Eigen::Ref<Eigen::ArrayXXd>& out) {
  if (out.rows() != z.rows() || out.cols() != z.cols()) {
    std::ostringstream msg;
    msg << what << ": output is " << out.rows() << "x" << out.cols() << " but z is " << z.rows()
        << "x" << z.cols();
    throw Error(msg.str());
  }
}

}  // namespace

std::string to_string(Activation activation) {
  return name_of(kNames, activation, "Activation");
}

Activation parse_activation(const std::string& text) {
  return value_named(kNames, text, "activation");
}

void apply(Activation activation, const Eigen::Ref<const Eigen::ArrayXXd>& z,
           Eigen::Ref<Eigen::ArrayXXd> out) {
  check_shape("apply", z, out);
  switch (activation) {
    case Activation::kTanh: out = z.tanh(); return;
    case Activation::kRelu: out = z.max(0.0); return;
    case Activation::kSigmoid: out = z.unaryExpr(&sigmoid); return;
    // log(1 + e^z) = log1p(e^−|z|) + max(z, 0): finite and accurate for any |z|.
    case Activation::kSoftplus: out = (-z.abs()).exp().log1p() + z.max(0.0); return;
    case Activation::kIdentity: out = z; return;
  }
}

void derivative(Activation activation, const Eigen::Ref<const Eigen::ArrayXXd>& z,
                Eigen::Ref<Eigen::ArrayXXd> out) {
  check_shape("derivative", z, out);
  switch (activation) {
    case Activation::kTanh: out = 1 - z.tanh().square(); return;
    case Activation::kRelu: out = (z > 0).cast<double>(); return;
    case Activation::kSigmoid: out = z.unaryExpr(&sigmoid_derivative); return;
    case Activation::kSoftplus: out = z.unaryExpr(&sigmoid); return;
    case Activation::kIdentity: out.setOnes(); return;
  }
}

void apply_with_derivative(Activation activation, Eigen::Ref<Eigen::ArrayXXd> z,
                           Eigen::Ref<Eigen::ArrayXXd> slope) {
  check_shape("apply_with_derivative", z, slope);
  switch (activation) {
    case Activation::kTanh:
      z = z.tanh();
      slope = 1 - z.square();
      return;
    case Activation::kRelu:
      z = z.max(0.0);
      slope = (z > 0).cast<double>();
      return;
    default:
      derivative(activation, z, slope);
      apply(activation, z, z);
  }
}

}  // namespace physgrad
