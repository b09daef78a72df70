// Learning from PyTorch: the structured rules' options (kfac, kfac-hig, lanczos-gn, lanczos-hig)
// checked by the library, and their first step on a given Mlp θ, batch and P = diag(s).
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <memory>

#include "bindings.hpp"
#include "physgrad/error.hpp"
#include "physgrad/learn/learning_update.hpp"
#include "physgrad/learn/stacked_jacobian.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "python_simulator.hpp"

namespace physgrad::python {

namespace {

bool is_structured(const std::string& rule) {
  return rule == "kfac" || rule == "kfac-hig" || rule == "lanczos-gn" || rule == "lanczos-hig";
}

// The rule built from the catalogue's defaults and `given`, as make_learning_update checks it.
std::unique_ptr<LearningUpdate> structured_rule(const std::string& rule, const py::dict& given) {
  if (!is_structured(rule)) {
    throw Error("structured rule '" + rule +
                "' is not kfac, kfac-hig, lanczos-gn or lanczos-hig");
  }
  const RuleSettings settings = rule_settings(given);
  check_rule_option_names(RuleKind::kLearning, rule, settings);
  return make_learning_update(rule, settings);
}

// The rule's params() (every option by name) for the given settings; Error for a bad one.
py::object structured_params(const std::string& rule, const py::dict& given) {
  return to_python(structured_rule(rule, given)->params());
}

// One step of `rule` on y = diag(s)·f(x; θ), f the Mlp of `widths` (tanh or `hidden` inside, the
// identity at the output): x is (B, n_in), dl_dy (B, m) with m = n_out = |s|. Δθ in the Mlp's
// order, [vec(W_l) column-major, b_l] per layer.
py::array_t<double> structured_mlp_step(const std::string& rule, const py::dict& given,
                                        const std::vector<Index>& widths,
                                        const std::string& hidden, const py::handle& theta,
                                        const py::handle& x, const py::handle& scales,
                                        const py::handle& dl_dy) {
  const std::unique_ptr<LearningUpdate> update = structured_rule(rule, given);
  Mlp network(widths, parse_activation(hidden), Activation::kIdentity);
  const Vector t = to_vector(theta, "structured_mlp_step", "theta");
  if (t.size() != network.num_parameters()) {
    throw Error("structured_mlp_step: θ has " + std::to_string(t.size()) + " entries, the Mlp " +
                std::to_string(network.num_parameters()));
  }
  network.parameters() = t;
  const Matrix inputs = to_columns(x, "structured_mlp_step", "x");
  if (inputs.rows() != network.input_dim()) {
    throw Error("structured_mlp_step: x must be (B, " + std::to_string(network.input_dim()) + ")");
  }
  const Index b = inputs.cols();
  const DiagonalScale physics(to_vector(scales, "structured_mlp_step", "scales"));
  const Index m = physics.output_dim();
  if (m != network.output_dim()) throw Error("structured_mlp_step: |s| differs from n_out");
  const Vector g = to_vector(dl_dy, "structured_mlp_step", "dl_dy");  // sample-major (B, m)
  if (g.size() != b * m) throw Error("structured_mlp_step: dl_dy must have B·m entries");
  auto cache = network.new_cache();
  const Matrix out = network.forward(inputs, *cache);
  std::vector<Matrix> cotangents;
  for (Index k = 0; k < m; ++k) {
    Matrix c = Matrix::Zero(m, b);
    c.row(k).setConstant(physics.scales()(k));
    cotangents.push_back(std::move(c));
  }
  BatchState state;
  state.batch_size = b;
  state.loss_gradient_y.resize(b * m);
  for (Index i = 0; i < b; ++i) {
    for (Index k = 0; k < m; ++k) state.loss_gradient_y(k * b + i) = g(i * m + k);
  }
  state.jacobian = std::make_shared<LocalJacobian>(network, *cache, physics, out,
                                                   std::move(cotangents));
  // A rule given samples refreshes from weighted factors (the batch as evaluate_batch gives it).
  state.gradient = state.jacobian->apply_transpose(state.loss_gradient_y);
  state.outputs = m;
  state.weighted_factors = [&](const std::vector<Matrix>& weights) {
    return network.dense_layer_factors(*cache,
                                       weighted_output_cotangents(physics, out, Matrix(), weights));
  };
  return to_numpy(update->step(state).delta);
}

}  // namespace

void bind_structured(py::module_& m) {
  m.def("_structured_params", &structured_params, py::arg("rule"), py::arg("settings"),
        "The options of kfac, kfac-hig, lanczos-gn or lanczos-hig, checked, by name.");
  m.def("_structured_mlp_step", &structured_mlp_step, py::arg("rule"), py::arg("settings"),
        py::arg("widths"), py::arg("hidden"), py::arg("theta"), py::arg("x"), py::arg("scales"),
        py::arg("dl_dy"),
        "The library's first step of a structured rule on an Mlp through P = diag(s).");
}

}  // namespace physgrad::python
