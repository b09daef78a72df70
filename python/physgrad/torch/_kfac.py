"""K-FAC and its half-inverse (the library's kfac, kfac-hig) as torch optimizers, for models whose
trainable layers are Linear, Conv1d and Conv2d: per layer JᵀJ ≈ A ⊗ S and
Δ[W b] = −lr·S^{−p}·∇[W b]·A^{−p}, p = (1+κ)/2, as KroneckerHigUpdate (kronecker_hig.hpp).

A layer's rows of [W b] are its output channels; its columns the entries of W's input (for a
convolution the in·k… entries of one input patch, in the order of unfold and of
weight.reshape(out, −1)) and then the bias. A frozen weight or bias has no column.
Normalisation (KFC, Grosse & Martens 2016, spatial positions as extra samples): with ā_ip the
input patch of sample i at output position p (and the bias's 1) and δ_ikp the cotangent ∂y_ik/∂z
of the layer's output at p,
    A = (1/B) Σ_i Σ_p ā_ip ā_ipᵀ,     S = (1/P) Σ_{i,k} Σ_p δ_ikp δ_ikpᵀ,
P the output positions of the layer (1 for Linear on (B, in) and for a convolution with one
output position, where the factors are the dense layer's). A Linear applied to (B, …, in) counts
the middle dimensions as positions.
With samples = K > 0 a refresh sums S over K directions per sample instead of the m outputs:
√(m/K)·Q_i e_j, Q_i (m × K) the orthonormal Q of a Gaussian matrix from the optimizer's own
generator (E[Q_i Q_iᵀ] = (K/m)·I, so E[S] is the exact S; exact for K = m); K backward sweeps
instead of m.
"""

import torch
import torch.nn.functional as F

from .. import _physgrad
from ._structured import StructuredRule, check_batch

_SUPPORTED = (torch.nn.Linear, torch.nn.Conv1d, torch.nn.Conv2d)


def _layers(rule, model, wanted):
    """[(path, module, weight trains, bias trains)] for every module holding a parameter in
    `wanted` (ids); Error naming the first layer that is not Linear, Conv1d or Conv2d."""
    layers = []
    for path, module in model.named_modules():
        own = [p for p in module.parameters(recurse=False) if id(p) in wanted]
        if not own:
            continue
        if not isinstance(module, _SUPPORTED):
            raise _physgrad.Error(
                f"{rule}: layer '{path}' ({type(module).__name__}) has trainable parameters; "
                "only Linear, Conv1d and Conv2d layers have Kronecker factors (freeze it)")
        if isinstance(module, (torch.nn.Conv1d, torch.nn.Conv2d)) and module.groups != 1:
            raise _physgrad.Error(f"{rule}: layer '{path}' ({type(module).__name__}) has "
                                  f"groups={module.groups}; only groups=1 is supported")
        bias = module.bias is not None and id(module.bias) in wanted
        layers.append((path, module, id(module.weight) in wanted, bias))
    return layers


def _patches(module, x):
    """The layer's input as rows ā (one per sample and output position), (B·P, D), and B."""
    batch = x.shape[0]
    if isinstance(module, torch.nn.Linear):
        return x.reshape(-1, x.shape[-1]), batch
    pad = module.padding
    if isinstance(pad, str) or module.padding_mode != "zeros":
        mode = "constant" if module.padding_mode == "zeros" else module.padding_mode
        x = F.pad(x, module._reversed_padding_repeated_twice, mode=mode)
        pad = (0,) * len(module.kernel_size)
    if isinstance(module, torch.nn.Conv2d):
        cols = F.unfold(x, module.kernel_size, dilation=module.dilation, padding=pad,
                        stride=module.stride)
    else:
        cols = F.unfold(x.unsqueeze(2), (1, module.kernel_size[0]),
                        dilation=(1, module.dilation[0]), padding=(0, pad[0]),
                        stride=(1, module.stride[0]))
    return cols.transpose(1, 2).reshape(-1, cols.shape[1]), batch


_DIRECTION_SEED = 20261129


def _sampled_directions(generator, samples, batch, m):
    """(K, B, m): direction j of sample i is √(m/K)·Q_i e_j, Q_i the Q of an m × K matrix of
    standard normals (float64, CPU, drawn with `generator`)."""
    gaussian = torch.randn(batch, m, samples, generator=generator, dtype=torch.float64)
    q, _ = torch.linalg.qr(gaussian)
    return (q * (m / samples) ** 0.5).permute(2, 0, 1)


def _cotangents(y, outputs, rows, directions=None):
    """∂(rows·y)/∂z for every layer output z: for each output direction (the m unit vectors e_k,
    or `directions`, (K, B, m)), the cotangent of every sample, batched over the directions; a
    list of (count·B·P, out) per layer."""
    batch, m = y.shape
    if directions is None:
        eye = torch.eye(m, dtype=y.dtype, device=y.device)
        directions = eye.unsqueeze(1).expand(m, batch, m)
    else:
        directions = directions.to(y.device, y.dtype)
    try:
        grads = torch.autograd.grad(y, outputs, directions, retain_graph=True,
                                    is_grads_batched=True)
    except RuntimeError:  # an operation without a batched backward: one direction at a time
        parts = [torch.autograd.grad(y, outputs, directions[k], retain_graph=True)
                 for k in range(directions.shape[0])]
        grads = [torch.stack(g) for g in zip(*parts)]
    return [rows(g) for g in grads]


def _channels_last(module, g):
    """(m, B, out, *positions) or (m, B, …, out) as (m·B·P, out)."""
    if isinstance(module, torch.nn.Linear):
        return g.reshape(-1, g.shape[-1])
    return g.movedim(2, -1).reshape(-1, g.shape[2])


def _power(factor, p, rcond, damping):
    """V f(Λ) Vᵀ, f(λ) = (λ + damping·λ_max)^{−p} for λ > rcond²·λ_max, else 0."""
    values, vectors = torch.linalg.eigh(factor)
    if values.numel() == 0:
        return factor
    largest = values.max()
    weights = torch.zeros_like(values)
    if largest > 0:
        kept = values > rcond * rcond * largest
        weights[kept] = (values[kept] + damping * largest) ** (-p)
    return (vectors * weights) @ vectors.T


class KFAC(StructuredRule):
    """K-FAC (κ = 1, the library's kfac): Δ[W b] = −lr·S^{−1}·∇[W b]·A^{−1} per layer, with the
    factor eigenvalues λ ≤ rcond²·λ_max dropped and the others damped by damping·λ_max; the
    factors refreshed every `refresh` steps as running averages (weight factor_decay for the
    old ones; the first refresh takes the batch's). KFAC(params, model, lr=None, **options):
    lr, kappa, rcond, damping, refresh, factor_decay, samples, each defaulting to the library's
    (physgrad.rule_defaults("kfac")); samples = K > 0 takes S from K random output directions
    per sample (module docstring), 0 from all m outputs.
    step(closure), closure from structured_closure."""

    rule = "kfac"

    def __init__(self, params, model, lr=None, **options):
        super().__init__(params, model, lr=lr, **options)
        wanted = {id(p) for _, p in self._trainable()}
        self._layers = _layers(self.rule, model, wanted)
        self._steps = 0
        self._factors = None  # [(A, S)] per layer, float64 on the CPU
        self._powers = None
        self._generator = torch.Generator().manual_seed(_DIRECTION_SEED)

    def _samples(self):
        return self.param_groups[0].get("samples", 0)

    def _batch_factors(self, batch):
        records = {}
        hooks = [module.register_forward_hook(
            lambda mod, args, out, path=path: records.__setitem__(path, (args[0], out)))
            for path, module, _, _ in self._layers]
        try:
            with torch.enable_grad():
                y = batch.forward().reshape(batch.dl_dy.shape)
        finally:
            for hook in hooks:
                hook.remove()
        outputs = [records[path][1] for path, _, _, _ in self._layers]
        gradients = self._gradients(y, batch)
        factors = []
        directions = None
        if self._samples() > 0:
            k, (count, m) = self._samples(), y.shape
            if k > m:
                raise _physgrad.Error(f"{self.rule}: samples {k} exceeds the {m} physics outputs "
                                      "per sample; nothing was changed")
            directions = _sampled_directions(self._generator, k, count, m)
        with torch.enable_grad():
            grads = _cotangents(y, outputs, lambda g: g, directions)
        for (path, module, weight, bias), g in zip(self._layers, grads):
            with torch.no_grad():
                rows, samples = _patches(module, records[path][0].detach())
                rows = rows.to("cpu", torch.float64)
                columns = [rows] if weight else []
                if bias:
                    columns.append(torch.ones(rows.shape[0], 1, dtype=torch.float64))
                a = torch.cat(columns, 1)
                delta = _channels_last(module, g.detach()).to("cpu", torch.float64)
                positions = rows.shape[0] // samples
                factors.append((a.T @ a / samples, delta.T @ delta / positions))
        return factors, gradients

    def _gradients(self, y, batch):
        """∇θ(mean loss) = Jᵀ·∂L/∂y of every trainable parameter of every layer, float64."""
        params = [p for _, module, w, b in self._layers
                  for p in ((module.weight,) if w else ()) + ((module.bias,) if b else ())]
        with torch.enable_grad():
            grads = torch.autograd.grad(y, params, batch.dl_dy, retain_graph=True,
                                        allow_unused=True)
        return {id(p): (torch.zeros_like(p) if g is None else g).detach().to("cpu", torch.float64)
                for p, g in zip(params, grads)}

    def _directions(self, gradients, powers):
        """{id(p): Δp} with lr 1: −S^{−p} G A^{−p} per layer."""
        out = {}
        for (_, module, weight, bias), (a_power, s_power) in zip(self._layers, powers):
            parts = []
            if weight:
                parts.append(gradients[id(module.weight)].reshape(module.weight.shape[0], -1))
            if bias:
                parts.append(gradients[id(module.bias)].reshape(-1, 1))
            step = -(s_power @ torch.cat(parts, 1) @ a_power)
            if weight:
                width = parts[0].shape[1]
                out[id(module.weight)] = step[:, :width].reshape(module.weight.shape)
            if bias:
                out[id(module.bias)] = step[:, -1]
        return out

    @torch.no_grad()
    def step(self, closure):
        with torch.enable_grad():
            batch = closure()
        check_batch(self.rule, batch)
        refreshing = self._steps % self._option("refresh") == 0
        factors = self._factors
        drawn = self._generator.get_state()  # put back if the step fails
        try:
            return self._step(batch, refreshing, factors)
        except BaseException:
            self._generator.set_state(drawn)
            raise

    def _step(self, batch, refreshing, factors):
        if refreshing:
            fresh, gradients = self._batch_factors(batch)
            if factors is not None:
                w = self._option("factor_decay")
                fresh = [(w * a0 + (1 - w) * a1, w * s0 + (1 - w) * s1)
                         for (a0, s0), (a1, s1) in zip(factors, fresh)]
            factors = fresh
            for index, (a, s) in enumerate(factors):
                if not (bool(torch.isfinite(a).all()) and bool(torch.isfinite(s).all())):
                    raise _physgrad.NumericalError(
                        f"{self.rule}: non-finite Kronecker factor of layer "
                        f"'{self._layers[index][0]}'; nothing was changed")
        else:
            with torch.enable_grad():
                y = batch.forward().reshape(batch.dl_dy.shape)
            gradients = self._gradients(y, batch)
        powers = self._powers
        if refreshing or powers is None:
            p = 0.5 * (1 + self._option("kappa"))
            rcond, damping = self._option("rcond"), self._option("damping")
            powers = [(_power(a, p, rcond, damping), _power(s, p, rcond, damping))
                      for a, s in factors]
        directions = self._directions(gradients, powers)
        pairs = self._trainable()
        self._apply(pairs, [directions[id(p)] for _, p in pairs])
        self._factors, self._powers = factors, powers
        self._steps += 1
        return batch.loss

    def state_dict(self):
        state = super().state_dict()
        state["physgrad"] = {"steps": self._steps,
                             "factors": None if self._factors is None else
                             [(a.clone(), s.clone()) for a, s in self._factors],
                             "generator": self._generator.get_state()}
        return state

    def load_state_dict(self, state_dict):
        state_dict = dict(state_dict)
        extra = state_dict.pop("physgrad", {})
        factors = extra.get("factors")
        if factors is not None and len(factors) != len(self._layers):
            raise _physgrad.Error(f"{self.rule}: the state has factors of {len(factors)} layers, "
                                  f"the model {len(self._layers)}")
        generator = torch.Generator().manual_seed(_DIRECTION_SEED)
        if extra.get("generator") is not None:
            generator.set_state(extra["generator"])
        super().load_state_dict(state_dict)
        self._generator = generator
        self._steps = int(extra.get("steps", 0))
        self._factors = None if factors is None else [(a.clone(), s.clone()) for a, s in factors]
        self._powers = None


class KFACHIG(KFAC):
    """K-FAC's half-inverse (κ = ½, the library's kfac-hig): each factor to the power −¾, so
    that Δθ = −lr·(A ⊗ S)^{−¾}·∇θL approximates HIG's −lr·(JᵀJ)^{−¾}·∇θL."""

    rule = "kfac-hig"
