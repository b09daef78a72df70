"""The κ-family made matrix-free (the library's lanczos-gn, lanczos-hig) as torch optimizers:
Δθ = −lr·Jᵀ f(J Jᵀ) ∂L/∂y, f(λ) = λ^{−(1+κ)/2} by q Lanczos steps on J Jᵀ from ∂L/∂y, as
LanczosHigUpdate (lanczos_hig.hpp). J is never formed: each step is one Jᵀc (a reverse-mode pass,
functorch.vjp) and one J w (a forward-mode pass, functorch.jvp) of y = simulate(model(inputs))
over the trainable parameters; any layer whose operations have both derivatives can train.
"""

import functorch
import torch

from .. import _physgrad
from ._structured import StructuredRule, check_batch

# The floor of the relative cut on the Ritz values (the library's kMinGramRcond).
_MIN_RCOND = 1e-7


def lanczos_function(multiply, b, steps, f):
    """‖b‖·Q S f(Λ) Sᵀ e₁ ≈ f(A) b from `steps` Lanczos steps of A (multiply(v) = A v), fully
    reorthogonalized (twice); stops early when the Krylov space is exhausted. Returns the
    coefficients c (f(A) b ≈ Q c) and the number of steps made."""
    n = b.numel()
    norm = float(b.norm())
    if norm == 0 or n == 0:
        return torch.zeros(0, dtype=torch.float64), 0
    steps = min(steps, n)
    basis = torch.zeros(n, steps, dtype=torch.float64)
    alpha, beta = [], []
    basis[:, 0] = b / norm
    scale, eps = 0.0, torch.finfo(torch.float64).eps
    made = 0
    for j in range(steps):
        w = multiply(basis[:, j])
        if not bool(torch.isfinite(w).all()):
            raise _physgrad.NumericalError("lanczos: non-finite product J Jᵀ q")
        alpha.append(float(basis[:, j] @ w))
        q = basis[:, :j + 1]
        for _ in range(2):
            w = w - q @ (q.T @ w)
        made = j + 1
        scale = max(scale, abs(alpha[-1]))
        if j + 1 == steps:
            break
        beta.append(float(w.norm()))
        scale = max(scale, beta[-1])
        if beta[-1] <= 8 * eps * n * scale:
            break
        basis[:, j + 1] = w / beta[-1]
    t = torch.diag(torch.tensor(alpha, dtype=torch.float64))
    if made > 1:
        off = torch.tensor(beta[:made - 1], dtype=torch.float64)
        t += torch.diag(off, 1) + torch.diag(off, -1)
    ritz, vectors = torch.linalg.eigh(t)
    return norm * (vectors @ (f(ritz) * vectors[0])), made


class LanczosGN(StructuredRule):
    """Gauss-Newton by q Lanczos steps (κ = 1, the library's lanczos-gn): Δθ = −lr·Jᵀ f(J Jᵀ) g,
    f(λ) = λ^{−1} on the Ritz values above rcond²·θ_max (rcond raised to 1e-7, and to √ε of the
    parameters' dtype, 3.5e-4 in float32), 0 below.
    LanczosGN(params, model, lr=None, **options): lr, kappa, rcond, products, each defaulting
    to the library's (physgrad.rule_defaults("lanczos-gn")). step(closure), closure from
    structured_closure. After a step, last_info holds the Lanczos steps made and the Ritz values
    kept."""

    rule = "lanczos-gn"

    def __init__(self, params, model, lr=None, **options):
        super().__init__(params, model, lr=lr, **options)
        self.last_info = None

    def _products(self, batch, pairs):
        """(J w, Jᵀ c) as functions of float64 vectors over the trainable parameters."""
        names = [self._names[id(p)] for _, p in pairs]
        values = tuple(p.detach() for _, p in pairs)
        fixed = {name: p.detach() for name, p in self._model.named_parameters()}
        shape = batch.dl_dy.shape

        def output(*theta):
            return batch.forward(dict(fixed, **dict(zip(names, theta)))).reshape(shape)

        y, pullback = functorch.vjp(output, *values)

        def split(w):
            parts, start = [], 0
            for v in values:
                parts.append(w[start:start + v.numel()].reshape(v.shape).to(v))
                start += v.numel()
            return tuple(parts)

        def forward(w):
            return functorch.jvp(output, values, split(w))[1].reshape(-1).to("cpu", torch.float64)

        def backward(c):
            parts = pullback(c.reshape(shape).to(y))
            return torch.cat([g.reshape(-1).to("cpu", torch.float64) for g in parts])

        return forward, backward

    @torch.no_grad()
    def step(self, closure):
        with torch.enable_grad():
            batch = closure()
        check_batch(self.rule, batch)
        pairs = self._trainable()
        with torch.enable_grad():
            forward, backward = self._products(batch, pairs)
        transposed = []

        def multiply(v):
            with torch.enable_grad():
                transposed.append(backward(v))
                return forward(transposed[-1])

        # The products carry the parameters' rounding: in float32 Ritz values below √ε·θ_max
        # are noise, and f would blow them up (in float64 √ε < 1e-7: the library's cut).
        lowest = min(torch.finfo(p.dtype).eps for _, p in pairs) if pairs else 0.0
        cut = max(self._option("rcond"), _MIN_RCOND, lowest ** 0.5)
        power = -0.5 * (1 + self._option("kappa"))
        kept = [0]

        def f(ritz):
            largest = float(ritz.max()) if ritz.numel() else 0.0
            keep = ritz > cut * cut * largest if largest > 0 else torch.zeros_like(ritz, dtype=bool)
            kept[0] = int(keep.sum())
            return torch.where(keep, ritz.clamp_min(1e-300) ** power, torch.zeros_like(ritz))

        g = batch.dl_dy.detach().reshape(-1).to("cpu", torch.float64)
        coefficients, made = lanczos_function(multiply, g, self._option("products"), f)
        total = sum(p.numel() for _, p in pairs)
        delta = (-(torch.stack(transposed[:made], 1) @ coefficients) if made
                 else torch.zeros(total, dtype=torch.float64))
        deltas, start = [], 0
        for _, p in pairs:
            deltas.append(delta[start:start + p.numel()].reshape(p.shape))
            start += p.numel()
        self._apply(pairs, deltas)
        self.last_info = {"lanczos_steps": made, "kept_directions": kept[0]}
        return batch.loss


class LanczosHIG(LanczosGN):
    """HIG by q Lanczos steps (κ = ½, the library's lanczos-hig): f(λ) = λ^{−¾}."""

    rule = "lanczos-hig"
