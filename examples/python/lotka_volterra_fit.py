"""Fits the four rates of a Lotka–Volterra predator–prey model to an observed trajectory with
physgrad's lm and with SciPy's least_squares (trf, lm) and L-BFGS-B, from the same start and
inside the same bounds (MINPACK's lm takes none); prints iterations, simulator evaluations, wall
time, the final loss, whether the iterates stayed inside the bounds (physgrad: every one; SciPy:
the result) and how many evaluations fell outside them (finite-difference probes included).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/lotka_volterra_fit.py [--quick]
"""

import argparse
import time

import numpy as np
import scipy.optimize

import physgrad

TRUE = np.array([1.1, 0.4, 0.4, 0.1])   # prey growth, predation, predator death, conversion
START = np.array([0.5, 0.2, 0.8, 0.2])
LOWER = np.array([0.05, 0.05, 0.05, 0.05])
UPPER = np.array([3.0, 3.0, 3.0, 3.0])


class LotkaVolterra:
    """y = the prey and predator counts at `samples` times in [0, T] (RK4 from (10, 5))."""

    name = "lotka-volterra"

    def __init__(self, samples, steps_per_sample, horizon=15.0):
        self.samples, self.steps = samples, steps_per_sample
        self.dt = horizon / (samples * steps_per_sample)
        self.output_dim = 2 * samples
        self.evaluations = 0
        self.outside = 0  # evaluations at rates outside the bounds (difference probes too)

    def forward(self, rates):
        self.evaluations += 1
        if np.any(rates < LOWER) or np.any(rates > UPPER):
            self.outside += 1
        a, b, c, d = rates

        def f(s):
            u, v = s
            return np.array([a * u - b * u * v, d * u * v - c * v])

        state = np.array([10.0, 5.0])
        out = np.empty((self.samples, 2))
        for i in range(self.samples):
            for _ in range(self.steps):
                k1 = f(state)
                k2 = f(state + 0.5 * self.dt * k1)
                k3 = f(state + 0.5 * self.dt * k2)
                k4 = f(state + self.dt * k3)
                state = state + self.dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            out[i] = state
        return out.reshape(-1)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="a coarse model (a few seconds)")
    args = parser.parse_args()
    samples, steps = (20, 5) if args.quick else (60, 10)
    observed = LotkaVolterra(samples, steps).forward(TRUE)

    rows = []

    def record(name, run):
        sim = LotkaVolterra(samples, steps)
        start = time.perf_counter()
        x, iterations, held = run(sim)
        seconds = time.perf_counter() - start
        loss = 0.5 * np.sum((sim.forward(x) - observed) ** 2)
        held = held and np.all(x >= LOWER) and np.all(x <= UPPER)
        rows.append((name, iterations, sim.evaluations - 1, seconds, loss, held, sim.outside,
                     np.max(np.abs(x - TRUE))))

    def physgrad_lm(sim, differences="central"):
        run = physgrad.minimize(sim, START, "lm", target=observed, bounds=(LOWER, UPPER),
                                max_iterations=200, function_tolerance=1e-12,
                                parameter_tolerance=1e-12, differences=differences)
        inside = np.all(run.x_history >= LOWER) and np.all(run.x_history <= UPPER)
        return run.x, run.iterations, inside

    def residual(sim):
        return lambda x: sim.forward(x) - observed

    def scipy_trf(sim):
        r = scipy.optimize.least_squares(residual(sim), START, bounds=(LOWER, UPPER),
                                         method="trf", xtol=1e-12, ftol=1e-12)
        return r.x, r.nfev, True

    def scipy_lm(sim):  # no bounds in MINPACK's lm
        r = scipy.optimize.least_squares(residual(sim), START, method="lm", xtol=1e-12,
                                         ftol=1e-12)
        return r.x, r.nfev, True

    def scipy_lbfgsb(sim):
        loss = lambda x: 0.5 * np.sum(residual(sim)(x) ** 2)
        r = scipy.optimize.minimize(loss, START, method="L-BFGS-B",
                                    bounds=list(zip(LOWER, UPPER)), options=dict(maxiter=500))
        return r.x, r.nit, True

    record("physgrad lm", physgrad_lm)
    record("physgrad lm fwd", lambda sim: physgrad_lm(sim, "forward"))  # 2-point differences
    record("scipy trf", scipy_trf)
    record("scipy lm", scipy_lm)
    record("scipy L-BFGS-B", scipy_lbfgsb)

    print(f"Lotka–Volterra rate fit: {samples} samples × 2 species, start {START}, "
          f"true {TRUE}")
    print(f"{'solver':16} {'iterations':>10} {'evaluations':>11} {'seconds':>8} "
          f"{'final loss':>11} {'in bounds':>9} {'outside':>7} {'max |x − true|':>14}")
    for name, iterations, evaluations, seconds, loss, held, outside, error in rows:
        print(f"{name:16} {iterations:>10} {evaluations:>11} {seconds:>8.3f} {loss:>11.3e} "
              f"{str(held):>9} {outside:>7} {error:>14.2e}")
    print("(scipy trf and lm count function evaluations as iterations; evaluations are "
          "forward passes, finite differences included)")
    for ours in rows[:2]:
        if not ours[5] or ours[7] > 1e-4:
            raise SystemExit(f"{ours[0]} did not reach the true rates inside the bounds")


if __name__ == "__main__":
    main()
