"""Two coupled oscillators, one 100× heavier: a network learns the forces that bring both to rest.

Each sample starts from a state s₀ = (x₁, v₁, x₂, v₂); a 4→32→32→16 MLP gives the forces on the
two masses over 8 control intervals; the simulator (symplectic Euler, a linear wall spring on
each mass, a coupling spring with a cubic term) returns the final state y, and the loss is
½‖y‖², the batch mean (B = 64). The heavy mass answers its forces 100× less: a badly scaled
problem, on which Adam, HIG and Gauss-Newton train for the same wall time. HIG's step size is
chosen by HIG.find_lr at the start. The simulator also serves bench/python_autodiff.py.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/two_oscillators.py [--quick]
"""

import argparse
import time

import torch

import physgrad.torch as pt

MASSES = (1.0, 100.0)
WALL = (1.0, 100.0)        # wall springs: both oscillators have the frequency 1
COUPLING, CUBIC = 0.5, 0.2
DT, SUBSTEPS, INTERVALS = 0.1, 5, 8


def step(x1, v1, x2, v2, f1=0.0, f2=0.0):
    """One symplectic Euler step: velocities from the forces, then positions from them."""
    d = x2 - x1
    coupling = COUPLING * d + CUBIC * d ** 3
    v1 = v1 + DT * (f1 - WALL[0] * x1 + coupling) / MASSES[0]
    v2 = v2 + DT * (f2 - WALL[1] * x2 - coupling) / MASSES[1]
    return x1 + DT * v1, v1, x2 + DT * v2, v2


def simulate(out):
    """(B, 20) → (B, 4): out = (16 forces, s₀) as Controller gives them; the final state."""
    x1, v1, x2, v2 = out[:, 16], out[:, 17], out[:, 18], out[:, 19]
    for k in range(INTERVALS):
        f1, f2 = out[:, 2 * k], out[:, 2 * k + 1]
        for _ in range(SUBSTEPS):
            x1, v1, x2, v2 = step(x1, v1, x2, v2, f1, f2)
    return torch.stack([x1, v1, x2, v2], dim=1)


class Controller(torch.nn.Module):
    """s₀ → (the MLP's 16 forces, s₀): the simulator needs the start of each sample too."""

    def __init__(self):
        super().__init__()
        self.mlp = torch.nn.Sequential(torch.nn.Linear(4, 32), torch.nn.Tanh(),
                                       torch.nn.Linear(32, 32), torch.nn.Tanh(),
                                       torch.nn.Linear(32, 16))

    def forward(self, s0):
        return torch.cat([self.mlp(s0), s0], dim=1)


def problem(batch=64, seed=0, dtype=torch.float32):
    torch.manual_seed(seed)
    model = Controller().to(dtype)
    inputs = torch.randn(batch, 4, dtype=dtype)
    targets = torch.zeros(batch, 4, dtype=dtype)
    return model, inputs, targets


def loss_fn(y, targets):
    return 0.5 * ((y - targets) ** 2).sum(dim=1).mean()


def train(rule, seconds=None, steps=None, seed=0):
    """(final loss, steps made, the loss curve [(t, loss)], the optimizer) after `seconds` of
    training or `steps` steps."""
    model, inputs, targets = problem(seed=seed)

    def loss():
        with torch.no_grad():
            return float(loss_fn(simulate(model(inputs)), targets))

    closure = pt.jacobian_closure(model, simulate, loss_fn, inputs, targets)
    if rule == "adam":
        opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    else:
        opt = (pt.HIG if rule == "hig" else pt.GN)(model.parameters(), rcond=1e-5)
        opt.find_lr(closure, loss)
    curve, made, start = [(0.0, loss())], 0, time.perf_counter()
    while (time.perf_counter() - start < seconds) if steps is None else made < steps:
        if rule == "adam":
            opt.zero_grad()
            loss_fn(simulate(model(inputs)), targets).backward()
            opt.step()
        else:
            opt.step(closure)
        made += 1
        curve.append((time.perf_counter() - start, loss()))
    return curve[-1][1], made, curve, opt


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="a few steps each, no comparison")
    parser.add_argument("--seconds", type=float, default=30.0, help="wall time of each rule")
    args = parser.parse_args()
    torch.set_num_threads(1)
    results = {}
    for rule in ("adam", "hig", "gn"):
        budget = dict(steps=40 if rule == "adam" else 4) if args.quick else dict(seconds=args.seconds)
        final, steps, curve, opt = train(rule, **budget)
        results[rule] = (final, curve)
        print(f"{rule:5s} {curve[-1][0]:6.2f} s: {steps:5d} steps, lr {opt.param_groups[0]['lr']:g}, "
              f"loss {curve[0][1]:.3e} → {final:.3e}")
    if args.quick:
        if not results["hig"][0] < results["hig"][1][0][1]:
            raise SystemExit("HIG did not lower the loss")
        return
    adam_final = results["adam"][0]
    for rule in ("hig", "gn"):
        reached = next((t for t, value in results[rule][1] if value <= adam_final), None)
        when = f"after {reached:.2f} s" if reached is not None else "not in its time"
        print(f"{rule}: Adam's final loss {adam_final:.3e} reached {when}")


if __name__ == "__main__":
    main()
