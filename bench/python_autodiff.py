"""Autodiff at the Python door, before and after, measured in one run (docs/python.md,
"Performance"): J-building for HIG against torch's own per-sample jacrev, minimize on a
TorchSimulator against a hand-written Jacobian and finite differences, SIP's step against Adam's.
"Before" runs the previous code paths, kept here: the per-sample Jacobian with a fixed chunk and
a float64 copy, a TorchSimulator without jacobian() (J from m VJPs) and without batched calls.
Not a test; one BLAS and torch thread.

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=build/python /usr/bin/python3 bench/python_autodiff.py
"""

import sys
import time
from pathlib import Path

import functorch
import numpy as np
import torch
from torch.nn.utils import stateless

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "examples" / "python"))
import physgrad  # noqa: E402
import physgrad.torch as pt  # noqa: E402
import two_oscillators as osc  # noqa: E402

from python_autodiff_before import (LegacySimulator, legacy_closure,  # noqa: E402
                                    legacy_per_sample_jacobian)


def best(function, repeats=5):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def torch_jacrev(model, inputs, chunk):
    """torch's own per-sample Jacobian: vmap over samples of jacrev in θ, `chunk` at a time."""
    names = [n for n, _ in model.named_parameters()]
    values = tuple(p.detach() for p in model.parameters())

    def output(theta, x):
        return osc.simulate(stateless.functional_call(model, dict(zip(names, theta)),
                                                      (x.unsqueeze(0),))).squeeze(0)

    jac = functorch.vmap(functorch.jacrev(output), in_dims=(None, 0))
    return [jac(values, inputs[s:s + chunk]) for s in range(0, inputs.shape[0], chunk)]


def jacobians():
    model, inputs, targets = osc.problem()
    print(f"J-building, two oscillators: 4→32→32→16 MLP, B = {inputs.shape[0]}, float32, "
          f"J {inputs.shape[0] * 4} × {sum(p.numel() for p in model.parameters())}")
    chunks = {c: best(lambda c=c: torch_jacrev(model, inputs, c)) for c in (8, 16, 32, 64)}
    top = min(chunks, key=chunks.get)
    ours = best(lambda: pt.per_sample_jacobian(model, osc.simulate, inputs))
    for c, t in chunks.items():
        print(f"  torch vmap(jacrev), chunk {c:2d}:        {1e3 * t:7.2f} ms")
    print(f"  physgrad per_sample_jacobian (auto):   {1e3 * ours:7.2f} ms   / torch's best "
          f"(chunk {top}) = {ours / chunks[top]:.2f}")
    old = {c: best(lambda c=c: legacy_per_sample_jacobian(model, osc.simulate, inputs, c))
           for c in (16, 64)}
    print(f"  before (chunk given, float64 copy): chunk 16 {1e3 * old[16]:.2f} ms, chunk 64 "
          f"{1e3 * old[64]:.2f} ms: chunk 16 / chunk 64 = {old[16] / old[64]:.2f}")
    for label, closure in (("before", legacy_closure(model, inputs, targets, 16)),
                           ("after", pt.jacobian_closure(model, osc.simulate, osc.loss_fn,
                                                         inputs, targets))):
        opt = pt.HIG(model.parameters(), lr=1e-9)  # a step that barely moves θ
        timed = []

        def timed_closure(closure=closure):
            start = time.perf_counter()
            out = closure()
            timed.append(time.perf_counter() - start)
            return out

        steps = []
        for _ in range(7):  # each step timed whole, its closure (J-building) inside it
            start = time.perf_counter()
            opt.step(timed_closure)
            steps.append((time.perf_counter() - start, timed[-1]))
        step, build = min(steps)
        print(f"  HIG step {label:6s}: {1e3 * step:6.2f} ms, of which J-building "
              f"{1e3 * build:6.2f} ms (the fastest of 7 steps)")


def trajectory(x):
    """(B, 4) initial states → (B, 200): both positions over 100 free steps."""
    x1, v1, x2, v2 = x[:, 0], x[:, 1], x[:, 2], x[:, 3]
    out = []
    for _ in range(100):
        x1, v1, x2, v2 = osc.step(x1, v1, x2, v2)
        out += [x1, x2]
    return torch.stack(out, dim=1)


class HandWritten:
    """The same simulator with its Jacobian written by hand: the tangents of the 4 initial
    values carried through every step (the step's derivative applied to them)."""

    name = "hand-written"

    def forward(self, x):
        return trajectory(torch.from_numpy(x).unsqueeze(0)).squeeze(0).numpy()

    def jacobian(self, x):
        x1, v1, x2, v2 = (torch.tensor(float(x[i]), dtype=torch.float64) for i in range(4))
        t = torch.eye(4, dtype=torch.float64)
        d1, e1, d2, e2 = t[0], t[1], t[2], t[3]  # ∂(x1, v1, x2, v2)/∂x0
        rows = []
        for _ in range(100):
            d = x2 - x1
            slope = osc.COUPLING + 3 * osc.CUBIC * d ** 2
            dd = d2 - d1
            e1 = e1 + osc.DT * (-osc.WALL[0] * d1 + slope * dd) / osc.MASSES[0]
            e2 = e2 + osc.DT * (-osc.WALL[1] * d2 - slope * dd) / osc.MASSES[1]
            d1, d2 = d1 + osc.DT * e1, d2 + osc.DT * e2
            x1, v1, x2, v2 = osc.step(x1, v1, x2, v2)
            rows += [d1, d2]
        return torch.stack(rows).numpy()


class ForwardOnly:
    """The same simulator, forward only: minimize makes J by differences of it."""

    name = "forward only"

    def forward(self, x):
        return trajectory(torch.from_numpy(x).unsqueeze(0)).squeeze(0).numpy()


def fits():
    truth = np.array([1.0, 0.0, -0.5, 0.02])
    target = trajectory(torch.from_numpy(truth).unsqueeze(0)).squeeze(0).numpy()
    start = np.array([0.5, 0.3, 0.0, 0.0])
    print("minimize: fit the 4 initial values of the oscillators to 100 steps of both positions "
          "(n = 4, m = 200)")
    sims = [("before: TorchSimulator, J from m VJPs", LegacySimulator(trajectory)),
            ("after: TorchSimulator, J by autodiff", pt.TorchSimulator(trajectory)),
            ("hand-written Jacobian", HandWritten()),
            ("central differences", ForwardOnly()),
            ("forward differences", ForwardOnly())]
    seconds = {}
    for rule, kwargs in (("gn", dict(max_iterations=3)),
                         ("lm", dict(max_iterations=200, relative_loss_tolerance=1e-20,
                                     function_tolerance=1e-14))):
        for label, sim in sims:
            differences = "forward" if label.startswith("forward") else "central"
            runs = [physgrad.minimize(sim, start, rule, target=target, differences=differences,
                                      **kwargs) for _ in range(1 if "before" in label else 3)]
            run = min(runs, key=lambda r: r.wall_seconds)  # the best of 3 (1 for the slow one)
            seconds[rule, label] = run.wall_seconds
            print(f"  {rule} {label:40s} {run.wall_seconds:8.3f} s  {run.iterations:3d} "
                  f"iterations, {run.counts['passes']:6d} passes, loss {run.loss:.2e}, "
                  f"{run.termination}")
        after, hand = seconds[rule, sims[1][0]], seconds[rule, sims[2][0]]
        print(f"  {rule}: before / after = {seconds[rule, sims[0][0]] / after:.1f}, "
              f"after / hand-written = {after / hand:.2f}")


def sip():
    torch.manual_seed(0)
    alpha = 0.01

    def simulate(x):
        return torch.stack([x[:, 0], alpha * x[:, 1]], 1)

    def inverse(y, x0):
        return torch.stack([y[:, 0], y[:, 1] / alpha], 1)

    inputs = torch.linspace(-1, 1, 64, dtype=torch.float64).unsqueeze(1)
    targets = simulate(torch.cat([torch.sin(2 * inputs), torch.cos(3 * inputs)], 1))
    print("SIP against Adam: 1–16–2 tanh network, P(x) = (x₁, 0.01·x₂), B = 64")

    def model():
        torch.manual_seed(0)
        return torch.nn.Sequential(torch.nn.Linear(1, 16), torch.nn.Tanh(),
                                   torch.nn.Linear(16, 2)).double()

    net = model()
    adam = torch.optim.Adam(net.parameters(), lr=1e-3)

    def adam_step():
        adam.zero_grad()
        (0.5 * ((simulate(net(inputs)) - targets) ** 2).sum(1).mean()).backward()
        adam.step()

    adam_time = best(adam_step, 20)
    print(f"  Adam step {1e3 * adam_time:8.2f} ms")
    for inverse_method in ("analytic", "lbfgs"):
        for label, sim in (("before", LegacySimulator(simulate, inverse)),
                           ("after", pt.TorchSimulator(simulate, inverse))):
            net = model()
            opt = pt.SIP(net.parameters(), sim, lr=1e-3, inverse=inverse_method)
            closure = pt.sip_closure(net, simulate, inputs, targets)
            t = best(lambda: opt.step(closure), 5 if inverse_method == "analytic" else 2)
            print(f"  SIP step, {inverse_method:8s} inverse, {label:6s} {1e3 * t:8.2f} ms = "
                  f"{t / adam_time:6.1f} × Adam's")


if __name__ == "__main__":
    torch.set_num_threads(1)
    parts = sys.argv[1:] or ["jacobians", "fits", "sip"]
    for part in parts:
        globals()[part]()
