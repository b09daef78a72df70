"""Random attacks on the Python door (run by test_fuzz.py in a process of its own, so that a crash
is seen): nested and cyclic option containers, options of another rule, hostile numbers,
non-finite steps and C-level callables. Prints a JSON tally by kind: attacks, held, and what
broke (a crash ends the process; an exception of another type, a non-finite parameter, a result
called "converged" that is not)."""

import json
import sys

import numpy as np
import torch

import physgrad
import physgrad.torch as pt

CLEAR = (physgrad.Error, physgrad.NumericalError)


def pick(rng, items):
    return items[int(rng.integers(len(items)))]


def leaf(rng):
    return pick(rng, [0, 1, -7, 2**63, 2**64, 0.5, float("nan"), float("inf"), "x", "0.5", None,
                      True, b"b", 1j, "", ","])


def container(rng, depth):
    if depth == 0 or rng.random() < 0.2:
        return leaf(rng)
    items = [container(rng, depth - 1) for _ in range(rng.integers(0, 4))]
    return tuple(items) if rng.random() < 0.3 else items


def attack_options(rng):
    kind = rng.integers(0, 3)
    if kind == 0:
        value = container(rng, int(rng.integers(1, 8)))
    elif kind == 1:  # cyclic, possibly through a tuple
        value = [leaf(rng)]
        inner = [value] if rng.random() < 0.5 else (value,)
        value.append(inner)
    else:  # deep
        value = [0.5]
        for _ in range(int(rng.integers(30, 5000))):
            value = [value]
    # The unknown option makes a well-formed value end in its error, not in a run.
    physgrad.run_experiment("scaled-toy", {"alpha": value, "no-such-option": 1}, progress=None)
    return "accepted: the unknown option did not stop the run"


# Each direct rule's options, as the catalogue lists them ("lr = 0.01, beta = 0.9").
OPTIONS = {rule["id"]: [part.split(" = ")[0] for part in rule["defaults"].split(", ")]
           for rule in physgrad.direct_rules()}


class Square:
    def forward(self, x):
        return np.asarray(x) ** 2 - 1.0


def attack_wrong_rule(rng):
    rule = pick(rng, list(OPTIONS))
    own = set(OPTIONS[rule])
    name = pick(rng, sorted({o for names in OPTIONS.values() for o in names} - own))
    try:
        physgrad.minimize(Square(), [0.5, 2.0], rule, max_iterations=3, **{name: leaf(rng)})
    except physgrad.Error as error:
        return "held" if name in str(error) else f"vague: {error}"
    return "accepted"  # an option of another rule ran: a wrong success


def attack_numbers(rng):
    x0 = pick(rng, [None, ["0.5", "1"], [1j, 2.0], np.array(["2020-01-01"], "datetime64[D]"),
                    [[0.5, 1.0], [1.0]], [0.5, 2.0], [True, False], object()])
    knobs = {pick(rng, ["max_iterations", "max_evaluations", "loss_tolerance", "max_seconds",
                        "max_history"]): leaf(rng) for _ in range(int(rng.integers(0, 3)))}
    run = physgrad.minimize(Square(), x0, "lm", **knobs)
    return check_converged(Square(), run)


def attack_step(rng):
    j = rng.normal(size=(4, 2, 5)) * pick(rng, [1.0, 1e-12, 1e150])
    if rng.random() < 0.3:
        j[rng.integers(0, 4), 0, rng.integers(0, 5)] = pick(rng, [np.nan, np.inf])
    lr = pick(rng, [1.0, 1e300, 1e308, float("inf"), float("nan"), -1.0])
    if rng.random() < 0.5:
        delta, _ = physgrad.jacobian_step(j, np.ones(8), lr=lr, kappa=pick(rng, [0.5, 1.0]))
        return "held" if np.all(np.isfinite(delta)) else "non-finite step returned"
    torch.manual_seed(int(rng.integers(0, 100)))
    dtype = pick(rng, [torch.float64, torch.float32, torch.float16])
    params = [torch.nn.Parameter(torch.randn(5).to(dtype))]
    before = params[0].detach().clone()
    opt = (pt.HIG if rng.random() < 0.5 else pt.GN)(params, lr=lr)
    try:
        opt.step(lambda: (0.0, torch.from_numpy(j), torch.ones(4, 2)))
    except CLEAR:
        return "held" if torch.equal(params[0], before) else "changed, then raised"
    return "held" if bool(torch.isfinite(params[0]).all()) else "non-finite parameter"


class CLevel:
    """forward and vjp are NumPy's C functions themselves."""

    def __init__(self, forward, vjp=None):
        self.forward = forward
        if vjp is not None:
            self.vjp = vjp


def attack_c_level(rng):
    forward = pick(rng, [np.exp, np.sin, np.sqrt, np.log, np.negative, np.tanh, np.square])
    sim = CLevel(forward, np.multiply if rng.random() < 0.3 else None)  # a wrong VJP at times
    rule = pick(rng, list(OPTIONS))
    x0 = rng.normal(size=int(rng.integers(1, 5))) * pick(rng, [1.0, 100.0])
    with np.errstate(all="ignore"):
        run = physgrad.minimize(sim, x0, rule, max_iterations=int(rng.integers(1, 40)),
                                loss_tolerance=pick(rng, [0.0, 1e-8, 1.0]),
                                relative_loss_tolerance=pick(rng, [0.0, 1e-3]),
                                function_tolerance=pick(rng, [0.0, 1e-6]),
                                gradient_tolerance=pick(rng, [0.0, 1e-6]),
                                differences=pick(rng, ["central", "forward"]))
    return check_converged(sim, run)


def check_converged(sim, run):
    """A "converged" run is held to its word: L(x) recomputed equals its loss, is finite, is at
    most L(x₀), and the named rule holds."""
    if not run.converged:
        return "held"
    with np.errstate(all="ignore"):
        loss = 0.5 * float(np.sum(np.asarray(sim.forward(run.x), dtype=float) ** 2))
    ok = np.isfinite(loss) and abs(loss - run.loss) <= 1e-12 * max(1.0, abs(loss))
    ok = ok and run.loss <= run.initial_loss
    if run.termination == "converged":
        ok = ok and "≤ loss_tolerance" in run.message
    return "held" if ok else f"wrong converged: {run.brief_report()}"


KINDS = {"option containers": attack_options, "wrong-rule options": attack_wrong_rule,
         "hostile numbers": attack_numbers, "non-finite steps": attack_step,
         "C-level callables": attack_c_level}


def main(seed, count):
    rng = np.random.default_rng(seed)
    tally = {kind: {"attacks": 0, "held": 0, "broke": []} for kind in KINDS}
    for i in range(count):
        kind = list(KINDS)[i % len(KINDS)]
        try:
            outcome = KINDS[kind](rng)  # "held", or what went wrong
        except CLEAR:
            outcome = "held"
        except Exception as error:  # noqa: BLE001 — any other type is what the fuzz looks for
            outcome = f"{type(error).__name__}: {error}"
        tally[kind]["attacks"] += 1
        if outcome == "held":
            tally[kind]["held"] += 1
        else:
            tally[kind]["broke"].append(outcome[:300])
    print(json.dumps(tally))


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]))
