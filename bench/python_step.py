"""The HIG step from Python against the same step from C++ and against a torch eigh-based HIG
step, on the oscillator reference Jacobian (J 512 × 2956), and the cost of a Python simulator
callback per evaluation. One BLAS/torch thread for everything (docs/python.md).

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=build/python /usr/bin/python3 bench/python_step.py
"""

import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import torch

import physgrad
import physgrad.torch as pt


def best_of(fn, repeats):
    """The fastest of `repeats` timed calls (seconds)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def torch_hig_step(j, g, lr, kappa, rcond):
    """−lr·Jᵀ U Λ^{−(1+κ)/2} Uᵀ g from the eigendecomposition of J Jᵀ (σ > rcond·σ_max kept)."""
    j2 = j.reshape(-1, j.shape[-1])
    lam, u = torch.linalg.eigh(j2 @ j2.T)
    keep = lam > (rcond ** 2) * lam[-1]
    u, lam = u[:, keep], lam[keep]
    return -lr * (j2.T @ (u @ (lam.pow(-(1 + kappa) / 2) * (u.T @ g.reshape(-1)))))


def main():
    torch.set_num_threads(1)
    ref = physgrad.reference_step("oscillators", 128, "hig")
    j = torch.from_numpy(ref["jacobian"])
    g = torch.from_numpy(ref["loss_gradient_y"])
    p = ref["params"]
    lr, kappa, rcond = p["lr"], p["kappa"], p["rcond"]
    opt = pt.HIG([torch.nn.Parameter(torch.zeros(j.shape[-1], dtype=torch.float64))], lr=lr,
                 rcond=rcond)
    repeats = 15
    python = best_of(lambda: opt.jacobian_step(j, g), repeats)
    cxx = min(physgrad._physgrad._time_jacobian_step(ref["jacobian"],
                                                     ref["loss_gradient_y"].reshape(-1),
                                                     lr, kappa, rcond, 1)
              for _ in range(repeats))
    torch_step = best_of(lambda: torch_hig_step(j, g, lr, kappa, rcond), repeats)
    ours, _ = opt.jacobian_step(j, g)
    theirs = torch_hig_step(j, g, lr, kappa, rcond).numpy()
    agreement = np.linalg.norm(ours - theirs) / np.linalg.norm(ours)
    print(f"HIG step on J {j.shape[0] * j.shape[1]} × {j.shape[2]} (oscillators, B = 128), "
          f"1 thread, OpenBLAS kernels {physgrad.blas_core() or '(not OpenBLAS)'}, "
          f"best of {repeats}:")
    print(f"  from Python (physgrad.torch.HIG): {python * 1e3:8.2f} ms")
    print(f"  from C++ (HigUpdate::step loop):   {cxx * 1e3:8.2f} ms   "
          f"Python / C++ = {python / cxx:.3f}")
    print(f"  torch eigh-based step:             {torch_step * 1e3:8.2f} ms   "
          f"torch / physgrad = {torch_step / python:.2f}   (results agree to {agreement:.1e})")
    # Variants of the eigensolve: precision auto (float only where the spectrum allows it, after
    # one step that tells), float forced (whatever the spectrum: an upper bound of what float
    # gains), and the dsyevd eigensolver that forms every eigenvector (the default before the
    # tridiagonal one).
    for variant_options in ({"precision": "auto"}, {"precision": "float"},
                            {"eigensolver": "full"}):
        variant = pt.HIG([torch.nn.Parameter(torch.zeros(j.shape[-1], dtype=torch.float64))],
                         lr=lr, rcond=rcond, **variant_options)
        _, variant.last_info = variant.jacobian_step(j, g)
        seconds = best_of(lambda: variant.jacobian_step(j, g), repeats)
        delta, info = variant.jacobian_step(j, g)
        label = ", ".join(f"{key}={value}" for key, value in variant_options.items())
        print(f"  {label:17s} ({info['precision']}, {info['eigensolver']}, kept "
              f"{info['rank']}, σ_max/σ_min,kept {info['sigma_max'] / info['sigma_min_kept']:.1e}): "
              f"{seconds * 1e3:8.2f} ms   torch / physgrad = {torch_step / seconds:.2f}   "
              f"(vs default: {np.linalg.norm(delta - ours) / np.linalg.norm(ours):.1e})")

    class Cheap:  # a simulator whose own work is negligible
        output_dim = 2

        def forward(self, x):
            return x

        def vjp(self, x, gy):
            return gy

    sim, x = Cheap(), np.array([0.48, 0.84])
    iterations = 2000
    run = physgrad.minimize(sim, x, "gd", max_iterations=iterations, lr=1e-6)
    through = best_of(lambda: physgrad.minimize(sim, x, "gd", max_iterations=iterations,
                                                lr=1e-6), 5)
    direct = best_of(lambda: [sim.forward(x) for _ in range(run.counts["passes"])], 5)
    per_pass = (through - direct) / run.counts["passes"]
    print(f"Python simulator callback: gd, {iterations} iterations, {run.counts['passes']} passes "
          f"({run.counts['forward']} forward, {run.counts['vjp']} VJP): "
          f"{through / run.counts['passes'] * 1e6:.1f} µs per pass through the library, "
          f"{per_pass * 1e6:.1f} µs above calling forward directly")


if __name__ == "__main__":
    main()
