"""physgrad from Python: inversion-based optimization (docs/python.md).

minimize() runs any direct rule of the library on a simulator written in Python; local_inverse()
solves P(x) = y near a guess; physgrad.torch holds the learning rules as torch optimizers.
"""

from . import _physgrad
from ._physgrad import (Error, LearningExperiment, MinimizeResult, NumericalError, blas_core,
                        blas_core_note, direct_rules, jacobian_step, learning_rules,
                        open_metrics, open_summary, reference_step, rule_defaults)
from ._results import Experiment, LocalInverseResult, RunOutcome, _experiments

__version__ = _physgrad.__version__


class BlasCoreWarning(RuntimeWarning):
    """OpenBLAS runs slower kernels than the CPU can (blas_core_note() says which to set)."""


def _warn_of_the_blas_core():
    """Warns once, on import, when OpenBLAS runs generic kernels on a CPU that can run faster
    ones (as the CLI prints its note); OPENBLAS_CORETYPE is read when OpenBLAS loads, so only
    the user can set it, before Python starts."""
    note = blas_core_note()
    if note:
        import warnings
        warnings.warn(note, BlasCoreWarning, stacklevel=3)


_warn_of_the_blas_core()

__all__ = ["Error", "NumericalError", "MinimizeResult", "LocalInverseResult", "RunOutcome",
           "Experiment", "minimize", "local_inverse", "direct_rules", "learning_rules",
           "rule_defaults",
           "jacobian_step", "reference_step", "experiments", "open_metrics", "open_summary",
           "run_experiment", "resume_experiment", "write_index", "LearningExperiment",
           "blas_core", "blas_core_note", "BlasCoreWarning", "__version__"]


def _bounds(bounds, n):
    """(lower, upper) from scipy's forms: a tuple (lower, upper) as least_squares takes it, a list
    of n pairs [(lo, hi), …] as minimize takes it (None for an open side), or a Bounds object."""
    if bounds is None:
        return None, None
    if hasattr(bounds, "lb") and hasattr(bounds, "ub"):  # scipy.optimize.Bounds
        return bounds.lb, bounds.ub
    if isinstance(bounds, list) and len(bounds) == n and all(
            isinstance(b, (tuple, list)) and len(b) == 2 for b in bounds):
        inf = float("inf")
        lower = [-inf if b[0] is None else b[0] for b in bounds]
        upper = [inf if b[1] is None else b[1] for b in bounds]
        return lower, upper
    if isinstance(bounds, (tuple, list)) and len(bounds) == 2:
        return bounds[0], bounds[1]
    raise Error(f"minimize: bounds {bounds!r} are neither (lower, upper) nor a list of {n} "
                "(lower, upper) pairs, one per variable")


def _size(x0):
    try:
        return len(x0)
    except TypeError:
        return 1


def minimize(sim, x0, rule="lm", *, target=None, loss_weight=1.0, bounds=None, x_scale=None,
             max_iterations=100, loss_tolerance=0.0, relative_loss_tolerance=0.0,
             gradient_tolerance=0.0, function_tolerance=0.0, parameter_tolerance=0.0,
             max_evaluations=0, max_seconds=0.0, max_history=100000,
             max_history_values=10000000, differences="central", callback=None,
             **rule_options):
    """Minimizes L(x) = (loss_weight/2)·‖sim.forward(x) − target‖² from x0 with rule `rule`.

    sim: an object with forward(x) -> y (1-D numpy arrays); optional vjp(x, gy) -> (∂P/∂x)ᵀgy,
    jacobian(x) -> (m, n), inverse(y, x0) -> x, time_reversal(y) -> x, output_dim and name.
    A missing Jacobian or VJP is formed by differences of forward: `differences` "central"
    (2n passes, error O(h²)) or "forward" (n + 1 passes, O(h)). target defaults to zeros.
    bounds: (lower, upper), each an array or None, or scipy.optimize.minimize's list of
    (lo, hi) pairs, or a scipy Bounds; x_scale the size of each variable. max_iterations ≥ 1;
    the tolerances and max_evaluations, max_seconds are off at 0 (C++ MinimizeOptions). The
    history keeps the start and the latest records: at most max_history, and at most
    max_history_values entries of x in all. callback(iteration, loss, x) after every
    iteration; returning True stops the run (False or None goes on). rule_options: the options
    of `rule` (physgrad.direct_rules()); an option `rule` does not take is an Error.
    """
    lower, upper = _bounds(bounds, _size(x0))
    stopping = dict(max_iterations=max_iterations, loss_tolerance=loss_tolerance,
                    relative_loss_tolerance=relative_loss_tolerance,
                    gradient_tolerance=gradient_tolerance, function_tolerance=function_tolerance,
                    parameter_tolerance=parameter_tolerance, max_evaluations=max_evaluations,
                    max_seconds=max_seconds, max_history=max_history,
                    max_history_values=max_history_values)
    return _physgrad._minimize(sim, x0, rule, target, loss_weight, lower, upper, x_scale,
                               stopping, callback, differences, rule_options)


def local_inverse(sim, y, x0, method="auto", *, tolerance=1e-10, max_iterations=200,
                  relative_tolerance=1e-8, function_tolerance=1e-6, rcond=1e-10, bounds=None):
    """The solution of sim.forward(x) = y nearest x0, a LocalInverseResult (x, residual,
    iterations, evaluations, counts, converged; also readable as a dict). method: "auto",
    "analytic" (sim.inverse), "time_reversal" (sim.time_reversal, anchored at x0), "lbfgs" or
    "ig" (inverse-gradient steps)."""
    lower, upper = _bounds(bounds, _size(x0))
    found = _physgrad._local_inverse(sim, y, x0, method, tolerance, max_iterations,
                                     relative_tolerance, function_tolerance, rcond, lower, upper)
    return LocalInverseResult(**found)


def experiments():
    """The registered experiments, as (name, description) pairs (also .name, ["name"])."""
    return _experiments(_physgrad.experiments())


def run_experiment(name, options=None, out="", progress=True, experiments=None):
    """Runs experiment NAME with options {name: value} (as `physgrad run NAME --name value`; a
    list is joined by commas) into the run folder `out`: a RunOutcome (folder, finished, report,
    stopped, summary; also readable as a dict). progress: True writes the lines that stay to
    sys.stderr, None is silent, a callable gets every progress line. Ctrl-C stops the run in
    order (a learning run keeps its checkpoint) and raises KeyboardInterrupt naming the folder.
    experiments: the script's own LearningExperiment objects; NAME is one of them or a
    reference experiment."""
    return RunOutcome(**_physgrad.run_experiment(name, {} if options is None else options, out,
                                                 progress, experiments))


def resume_experiment(folder, progress=True, experiments=None):
    """Continues the unfinished run in `folder` (as `physgrad resume FOLDER`): a RunOutcome.
    experiments: as in run_experiment (a run of the script's own experiment needs it again)."""
    return RunOutcome(**_physgrad.resume_experiment(folder, progress, experiments))


def write_index(folder, experiments=None):
    """Writes FOLDER/index.html over the run folders in FOLDER (as `physgrad report FOLDER`);
    returns {"folders": how many, "page": its path}. experiments: as in run_experiment."""
    return _physgrad.write_index(folder, experiments)
