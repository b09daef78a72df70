"""physgrad from Python: inversion-based optimization (docs/python.md).

minimize() runs any direct rule of the library on a simulator written in Python; local_inverse()
solves P(x) = y near a guess; physgrad.torch holds the learning rules as torch optimizers.
"""

from ._physgrad import (Error, MinimizeResult, NumericalError, blas_core, blas_core_note,
                        direct_rules, experiments, jacobian_step, learning_rules, open_metrics,
                        open_summary, reference_step, resume_experiment, run_experiment)
from . import _physgrad

__all__ = ["Error", "NumericalError", "MinimizeResult", "minimize", "local_inverse",
           "direct_rules", "learning_rules", "jacobian_step", "reference_step", "experiments",
           "open_metrics", "open_summary", "run_experiment", "resume_experiment", "blas_core",
           "blas_core_note"]


def _bounds(bounds):
    if bounds is None:
        return None, None
    lower, upper = bounds
    return lower, upper


def minimize(sim, x0, rule="lm", *, target=None, loss_weight=1.0, bounds=None, x_scale=None,
             max_iterations=100, loss_tolerance=0.0, relative_loss_tolerance=0.0,
             gradient_tolerance=0.0, function_tolerance=0.0, parameter_tolerance=0.0,
             max_evaluations=0, max_seconds=0.0, callback=None, **rule_options):
    """Minimizes L(x) = (loss_weight/2)·‖sim.forward(x) − target‖² from x0 with rule `rule`.

    sim: an object with forward(x) -> y (1-D numpy arrays); optional vjp(x, gy) -> (∂P/∂x)ᵀgy,
    jacobian(x) -> (m, n), inverse(y, x0) -> x, time_reversal(y) -> x, output_dim and name.
    A missing Jacobian or VJP is formed by central differences of forward. target defaults to
    zeros. bounds = (lower, upper), each an array or None; x_scale the size of each variable.
    The tolerances and budgets are those of the C++ MinimizeOptions (0 = off). callback(iteration,
    loss, x) after every iteration; returning True stops the run. rule_options: lr, beta, beta1,
    beta2, epsilon, rcond, memory, c1, c2, initial_damping, min_damping, inverse ("auto",
    "analytic", "time_reversal", "lbfgs", "ig"), inverse_tolerance, inverse_iterations,
    inverse_relative_tolerance, inverse_function_tolerance, inverse_rcond.
    """
    lower, upper = _bounds(bounds)
    return _physgrad._minimize(sim, x0, rule, target, float(loss_weight), lower, upper, x_scale,
                               int(max_iterations), float(loss_tolerance),
                               float(relative_loss_tolerance), float(gradient_tolerance),
                               float(function_tolerance), float(parameter_tolerance),
                               int(max_evaluations), float(max_seconds), callback, rule_options)


def local_inverse(sim, y, x0, method="auto", *, tolerance=1e-10, max_iterations=200,
                  relative_tolerance=1e-8, function_tolerance=1e-6, rcond=1e-10, bounds=None):
    """The solution of sim.forward(x) = y nearest x0: {"x", "residual", "iterations",
    "evaluations", "counts", "converged"}. method: "auto", "analytic" (sim.inverse),
    "time_reversal" (sim.time_reversal, anchored at x0), "lbfgs" or "ig" (inverse-gradient steps)."""
    lower, upper = _bounds(bounds)
    return _physgrad._local_inverse(sim, y, x0, method, float(tolerance), int(max_iterations),
                                    float(relative_tolerance), float(function_tolerance),
                                    float(rcond), lower, upper)
