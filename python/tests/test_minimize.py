# physgrad.minimize and physgrad.local_inverse on simulators written in Python.
import numpy as np
import pytest

import physgrad


@pytest.mark.parametrize("rule", ["newton", "gn", "lm", "ig", "pg"])
def test_inversion_rules_do_not_see_the_scale(scaled_toy, rule):
    # The inversion rules take the same path whatever α: the iterations to L ≤ 1e-12·L(x₀) do
    # not change.
    runs = [physgrad.minimize(scaled_toy(alpha), [0.48, 0.84], rule, max_iterations=200,
                              relative_loss_tolerance=1e-12) for alpha in (1.0, 100.0)]
    assert all(run.converged for run in runs), [run.brief_report() for run in runs]
    assert runs[0].iterations == runs[1].iterations


def test_gradient_descent_sees_the_scale_and_x_scale_removes_it(scaled_toy):
    kwargs = dict(max_iterations=2000, loss_tolerance=1e-12, lr=0.5)
    plain = physgrad.minimize(scaled_toy(1.0), [0.48, 0.84], "gd", **kwargs)
    scaled = physgrad.minimize(scaled_toy(30.0), [0.48, 0.84 / 30], "gd",
                               **dict(kwargs, lr=0.5 / 900))
    rescaled = physgrad.minimize(scaled_toy(30.0), [0.48, 0.84 / 30], "gd",
                                 x_scale=[1.0, 1 / 30.0], **kwargs)
    assert plain.converged and rescaled.converged
    assert not scaled.converged or scaled.iterations > 100 * plain.iterations
    assert rescaled.iterations == plain.iterations


def test_every_direct_rule_runs_and_lowers_the_loss(scaled_toy):
    rules = [rule["id"] for rule in physgrad.direct_rules()]
    assert {"gd", "adam", "newton", "bfgs", "lbfgs", "gn", "lm", "ig", "pg"} <= set(rules)
    for rule in rules:
        run = physgrad.minimize(scaled_toy(10.0), [0.48, 0.84], rule, max_iterations=30)
        assert run.loss < run.initial_loss, run.full_report()
        assert run.loss_history.shape == (len(run.x_history),)
        assert run.loss_history[0] == run.initial_loss
        assert run.rule == rule
        assert run.counts["passes"] > 0 and run.evaluations > 0
        assert rule in run.full_report() and run.brief_report().startswith(rule)


def test_missing_derivatives_come_from_finite_differences(scaled_toy):
    exact = physgrad.minimize(scaled_toy(10.0), [0.48, 0.84], "lm", loss_tolerance=1e-20)
    numeric = physgrad.minimize(scaled_toy(10.0, analytic=False), [0.48, 0.84], "lm",
                                loss_tolerance=1e-20)
    assert numeric.converged and exact.converged
    np.testing.assert_allclose(numeric.x, exact.x, atol=1e-9)
    assert numeric.iterations == exact.iterations


def test_bounds_hold_on_every_iterate():
    class Quadratic:  # minimum at (2, -3), outside the box
        def forward(self, x):
            return np.array([x[0] - 2.0, 10.0 * (x[1] + 3.0)])

    lower, upper = np.array([-1.0, -1.0]), np.array([1.0, 1.0])
    for rule in ("lm", "gn", "lbfgs", "gd", "newton"):
        options = dict(lr=0.001) if rule == "gd" else {}
        run = physgrad.minimize(Quadratic(), [0.0, 0.0], rule, bounds=(lower, upper),
                                max_iterations=50, **options)
        assert np.all(run.x_history >= lower) and np.all(run.x_history <= upper), rule
        if rule != "gd":
            np.testing.assert_allclose(run.x, [1.0, -1.0], atol=1e-8, err_msg=rule)
            assert run.at_bounds == 2


def test_tolerances_and_budgets_end_the_run(scaled_toy):
    run = physgrad.minimize(scaled_toy(100.0), [0.48, 0.84], "gd", lr=1e-5, max_evaluations=7)
    assert run.termination == "max_evaluations" and run.counts["passes"] <= 7
    run = physgrad.minimize(scaled_toy(1.0), [0.48, 0.84], "lm", gradient_tolerance=1e-6)
    assert run.termination == "gradient_tolerance"


class Failing(Exception):
    pass


class Breaks:
    """Raises `error` from `method` on its `after`-th call."""

    def __init__(self, method, error, after):
        self.calls, self.method, self.error, self.after = 0, method, error, after

    def _count(self, name):
        if name == self.method:
            self.calls += 1
            if self.calls >= self.after:
                raise self.error

    def forward(self, x):
        self._count("forward")
        return np.array([x[0], 3.0 * x[1]])

    def vjp(self, x, gy):
        self._count("vjp")
        return np.array([gy[0], 3.0 * gy[1]])


@pytest.mark.parametrize("method", ["forward", "vjp"])
def test_a_callback_error_reaches_python_as_itself(method):
    with pytest.raises(Failing) as raised:
        physgrad.minimize(Breaks(method, Failing("the solver broke"), 4), [1.0, 1.0], "lbfgs")
    assert type(raised.value) is Failing
    text = str(raised.value)
    assert text.startswith("the solver broke") and "rule lbfgs" in text and method in text
    assert "iteration " in text


def test_a_keyerror_keeps_its_type_and_the_iteration_is_named():
    with pytest.raises(KeyError) as raised:
        physgrad.minimize(Breaks("forward", KeyError("k"), 1), [1.0, 1.0], "lm")
    assert "rule lm, iteration 0" in str(raised.value)


def test_the_iteration_callback_may_stop_the_run_or_raise(scaled_toy):
    seen = []
    run = physgrad.minimize(scaled_toy(1.0), [0.48, 0.84], "gd",
                            callback=lambda i, loss, x: seen.append(i) or i == 3)
    assert run.termination == "stopped" and seen == [0, 1, 2, 3]

    def bad(i, loss, x):
        if i == 2:
            raise RuntimeError("callback failed")
        return False
    with pytest.raises(RuntimeError, match="callback failed.*rule gd, iteration 2"):
        physgrad.minimize(scaled_toy(1.0), [0.48, 0.84], "gd", callback=bad)


def test_a_wrong_sized_return_is_the_librarys_size_error():
    class Short:
        output_dim = 2

        def forward(self, x):
            return np.array([x[0], x[1], 0.0])

    with pytest.raises(physgrad.Error, match="forward returned 3 entries, expected 2"):
        physgrad.minimize(Short(), [1.0, 1.0], "gn")
    assert issubclass(physgrad.Error, ValueError)


def test_bad_input_is_a_one_line_error(scaled_toy):
    with pytest.raises(physgrad.Error, match="gd: unknown option 'lrate'"):
        physgrad.minimize(scaled_toy(1.0), [0.5, 0.5], "gd", lrate=0.1)
    with pytest.raises(physgrad.Error, match="nope"):
        physgrad.minimize(scaled_toy(1.0), [0.5, 0.5], "nope")
    with pytest.raises(physgrad.Error, match="x0"):
        physgrad.minimize(scaled_toy(1.0), [0.5, 0.5], "lm", bounds=([0.0, 0.0], [0.1, 1.0]))


def test_local_inverse_by_every_method(scaled_toy):
    class Leapfrogless:  # P(x) = 2x, time reversal R(y) = y / 2
        def forward(self, x):
            return 2.0 * np.asarray(x)

        def time_reversal(self, y):
            return 0.5 * np.asarray(y)

    y = np.array([0.3, -1.2])
    for sim, method in [(scaled_toy(4.0), "analytic"), (Leapfrogless(), "time_reversal"),
                        (scaled_toy(4.0, analytic=False), "lbfgs"),
                        (scaled_toy(4.0, analytic=False), "ig")]:
        result = physgrad.local_inverse(sim, y, [0.0, 0.0], method)
        assert result["converged"], method
        np.testing.assert_allclose(sim.forward(result["x"]), y, atol=1e-8, err_msg=method)


def test_pg_through_the_python_inverse(scaled_toy):
    run = physgrad.minimize(scaled_toy(1000.0), [0.48, 0.84], "pg", inverse="analytic",
                            loss_tolerance=1e-20)
    assert run.converged and run.counts["inverses"] > 0


def test_the_best_iterate_is_kept_when_newton_walks_away_from_it():
    class Atan:  # Newton's step on ½ atan(x)² overshoots from |x| > 1.39: the iterates grow
        def forward(self, x):
            return np.arctan(x)

        def jacobian(self, x):
            return np.array([[1.0 / (1.0 + x[0] ** 2)]])

    run = physgrad.minimize(Atan(), [1.5], "gn", max_iterations=6)
    assert run.loss > run.initial_loss  # the last iterate is worse than the start
    assert run.best_iteration == 0 and run.best_loss == run.initial_loss
    np.testing.assert_array_equal(run.best_x, [1.5])
    good = physgrad.minimize(Atan(), [0.5], "gn", max_iterations=6)
    assert good.best_iteration == good.iterations and good.best_loss == good.loss


def test_scipy_style_bounds_and_forward_differences(scaled_toy):
    pairs = physgrad.minimize(scaled_toy(10.0), [0.48, 0.84], "lm", bounds=[(0, 1), (0.5, None)])
    tupled = physgrad.minimize(scaled_toy(10.0), [0.48, 0.84], "lm",
                               bounds=([0, 0.5], [1, np.inf]))
    np.testing.assert_array_equal(pairs.x, tupled.x)
    np.testing.assert_allclose(pairs.x, [0.0, 0.5], atol=1e-8)
    central = physgrad.minimize(scaled_toy(10.0, analytic=False), [0.48, 0.84], "gn",
                                max_iterations=1)
    forward = physgrad.minimize(scaled_toy(10.0, analytic=False), [0.48, 0.84], "gn",
                                max_iterations=1, differences="forward")
    # One Jacobian: 2n = 4 difference passes, or n + 1 = 3; the forward passes of the loss
    # (start, new point) come on top, and passes count each call of the object.
    assert central.counts["passes"] - forward.counts["passes"] == 1
    assert central.counts["forward"] == central.counts["passes"] == 4 + central.evaluations
    np.testing.assert_allclose(forward.x, central.x, atol=1e-6)
    with pytest.raises(physgrad.Error, match="differences 'backward'"):
        physgrad.minimize(scaled_toy(1.0), [0.5, 0.5], "gn", differences="backward")
