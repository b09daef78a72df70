# Hostile input at the Python door: each attack ends in a clear one-line error (or a clean stop),
# never a crash, an unbounded wait or memory, a half-applied update or a non-finite parameter.
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
import torch

import physgrad
import physgrad.torch as pt


def _run_python(code, timeout=60):
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=timeout, env=dict(os.environ))


@pytest.mark.parametrize("make,error", [
    ("l = [1]; l.append(l)", "option alpha: the list contains itself"),
    ("l = [1]\nfor _ in range(60000): l = [l]", "option alpha: lists nested deeper than 32"),
    ("l = [[0.5, 2]] * 3; l = (l, [l, [l]])", "--alpha: '0.5' is listed twice"),  # shared, no cycle
    ("l = ['1' * 600000, '2' * 600000]", "option alpha: more than 1048576 characters")])
def test_nested_and_cyclic_option_lists_are_errors_not_crashes(make, error):
    code = (f"import physgrad\n{make}\n"
            "try:\n    physgrad.run_experiment('scaled-toy', {'alpha': l}, progress=None)\n"
            "except physgrad.Error as e:\n    print('Error:', e)\n")
    done = _run_python(code)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.startswith("Error: " + error), done.stdout


def test_a_run_folder_file_that_is_a_fifo_a_device_a_directory_or_too_large_is_refused(tmp_path):
    os.mkfifo(tmp_path / "metrics.csv")
    os.symlink("/dev/zero", tmp_path / "summary.json")
    start = time.monotonic()
    with pytest.raises(physgrad.Error, match=r"open_metrics: .*metrics.csv is not a regular file"):
        physgrad.open_metrics(str(tmp_path))
    with pytest.raises(physgrad.Error, match=r"open_summary: .*summary.json is not a regular file"):
        physgrad.open_summary(str(tmp_path))
    assert time.monotonic() - start < 5
    other = tmp_path / "other"
    (other / "metrics.csv").mkdir(parents=True)
    with pytest.raises(physgrad.Error, match="is a directory"):
        physgrad.open_metrics(str(other))
    with open(other / "summary.json", "wb") as big:
        big.truncate(9 << 20)  # sparse: 9 MiB of zeros take no disk
    with pytest.raises(physgrad.Error, match="more than the 8388608 allowed"):
        physgrad.open_summary(str(other))
    (other / "summary.json").write_text("[" * 100 + "]" * 100)
    with pytest.raises(physgrad.Error, match="nested deeper than 64"):
        physgrad.open_summary(str(other))


class Exp:
    """forward is NumPy's exp itself: a C function, no Python code runs in a pass."""
    forward = staticmethod(np.exp)


def test_ctrl_c_stops_minimize_with_a_c_level_forward():
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            physgrad.minimize(Exp(), np.zeros(200), "gd", lr=1e-12, max_iterations=10**9,
                              max_seconds=15.0)
    finally:
        timer.cancel()
    assert time.monotonic() - start < 5.0


def test_minimize_keeps_a_bounded_history(scaled_toy):
    run = physgrad.minimize(scaled_toy(100.0), [0.48, 0.84], "gd", lr=1e-6, max_iterations=50,
                            max_history=5)
    assert run.iterations == 50 and len(run.loss_history) == 5 and run.x_history.shape == (5, 2)
    assert run.history_dropped == 51 - 5
    assert run.loss_history[0] == run.initial_loss and run.loss_history[-1] == run.loss
    assert list(run.history_iterations) == [0, 47, 48, 49, 50]
    assert "46 dropped (max_history)" in run.full_report()

    class Linear:  # n = 10⁵: the default limit of 10⁷ stored entries keeps 100 records
        def forward(self, x):
            return x

        def vjp(self, x, gy):
            return gy

    run = physgrad.minimize(Linear(), np.ones(100000), "gd", lr=1e-3, max_iterations=150)
    assert len(run.loss_history) == 100 and run.history_dropped == 51
    with pytest.raises(physgrad.Error, match="max_history"):
        physgrad.minimize(Linear(), [1.0], "gd", max_history=1)


def _model(dtype=torch.float64):
    torch.manual_seed(0)
    return torch.nn.Sequential(torch.nn.Linear(2, 3), torch.nn.Tanh(),
                               torch.nn.Linear(3, 2)).to(dtype)


def _closure(model, scale=1.0):
    inputs = torch.linspace(-1, 1, 16, dtype=next(model.parameters()).dtype).reshape(8, 2)
    targets = torch.ones(8, 2, dtype=inputs.dtype)
    simulate = lambda x: scale * x  # noqa: E731
    return pt.jacobian_closure(model, simulate, lambda y, t: 0.5 * ((y - t) ** 2).sum(1).mean(),
                               inputs, targets)


@pytest.mark.parametrize("rule", [pt.HIG, pt.GN])
def test_a_step_that_would_write_a_non_finite_parameter_is_refused(rule):
    model = _model()
    before = [p.detach().clone() for p in model.parameters()]
    with pytest.raises(physgrad.NumericalError, match="non-finite.*nothing was changed"):
        rule(model.parameters(), lr=1e308).step(_closure(model, scale=1e-12))
    half = _model().half()
    half_before = [p.detach().clone() for p in half.parameters()]
    closure = _closure(_model(), scale=1e-12)  # J ≈ 1e-12: |Δθ| ≥ 1e6, beyond float16

    def float16_closure():
        loss, j, g = closure()
        return loss, j, g

    with pytest.raises(physgrad.NumericalError, match=r"parameter \d .*float16.*nothing was"):
        rule(half.parameters(), lr=1.0).step(float16_closure)
    for p, b in zip(list(model.parameters()) + list(half.parameters()), before + half_before):
        assert torch.equal(p, b)


def test_jacobian_step_refuses_a_non_finite_step_and_names_nan_in_j():
    j = np.random.default_rng(0).normal(size=(4, 2, 3))
    g = np.ones(8)
    with pytest.raises(physgrad.NumericalError, match=r"the step .*lr 1e\+308.* not finite"):
        physgrad.jacobian_step(j * 1e-6, g, lr=1e308)
    j[1, 0, 2] = np.nan
    with pytest.raises(physgrad.NumericalError,
                       match="1 non-finite entries, the first nan at sample 1, output 0, parameter 2"):
        physgrad.jacobian_step(j, g)


def test_a_jacobian_of_the_wrong_width_changes_nothing():
    model = _model()
    before = [p.detach().clone() for p in model.parameters()]
    closure = _closure(model)

    def narrow():
        loss, j, g = closure()
        return loss, j[:, :, :-3].contiguous(), g

    with pytest.raises(physgrad.Error, match="3 columns|columns, the trainable parameters 17"):
        pt.HIG(model.parameters()).step(narrow)
    for p, b in zip(model.parameters(), before):
        assert torch.equal(p, b)


def test_smaller_mistakes_are_clear_errors(scaled_toy):
    sim = scaled_toy(1.0)
    with pytest.raises(physgrad.Error, match="lm: unknown option 'lr'"):
        physgrad.minimize(sim, [0.5, 0.5], "lm", lr="abc")
    with pytest.raises(physgrad.Error, match=r"max_evaluations is 9223372036854775808, expected an"):
        physgrad.minimize(sim, [0.5, 0.5], "lm", max_evaluations=2**63)
    with pytest.raises(physgrad.Error, match=r"rule option memory is 18446744073709551616"):
        physgrad.minimize(sim, [0.5, 0.5], "lbfgs", memory=2**64)
    with pytest.raises(physgrad.Error, match=r"callback returned 'stop' \(str\)"):
        physgrad.minimize(sim, [0.5, 0.5], "lm", callback=lambda i, loss, x: "stop")
    for x0, kind in [(None, "NoneType"), (["0.5", "1"], "list of text"),
                     (np.array(["2020-01-01"], dtype="datetime64[D]"), "ndarray of dates"),
                     ([0.5 + 1j, 0.5], "list of complex numbers")]:
        with pytest.raises(physgrad.Error, match=f"x0 returned {kind}, expected an array"):
            physgrad.minimize(sim, x0, "lm")
    with pytest.raises(physgrad.Error, match=r"max_iterations must be ≥ 1|max_iterations is 0"):
        physgrad.minimize(sim, [0.5, 0.5], "lm", max_iterations=0)
