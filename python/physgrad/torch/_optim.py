"""HIG and Gauss-Newton as torch optimizers: Δθ = −lr·J^{−κ}·∂L/∂y (κ = ½ and 1) by HigUpdate.

They follow torch.optim: param groups (each with its own lr; the one inversion shares rcond,
backend, precision and eigensolver), frozen parameters (requires_grad=False) skipped, options
checked when the optimizer or a group is made, state_dict() round trip, parameters of any dtype
and device. The step runs where the library runs (CPU, double); nothing is written until the
whole update is known to be finite in every parameter's own dtype.
"""

import torch

from .. import _physgrad
from ._jacobian import per_sample_jacobian, trainable

# Options every group must share: the step inverts one Jacobian over all of them.
_SHARED = ("rcond", "backend", "precision", "eigensolver")


class _JacobianRule(torch.optim.Optimizer):
    """Δθ = −lr·J^{−κ}·∂L/∂y over the trainable parameters of all groups, in their order.

    step(closure): closure() returns (loss, J, dL_dy), J of shape (B, m, P) over the trainable
    parameters (P their entries, in order, each flattened) and dL_dy of shape (B, m),
    ∂(mean loss)/∂y; jacobian_closure makes one. A float64 or float32 CPU J that is
    C-contiguous is read where it lies.
    """

    rule = "hig"

    def __init__(self, params, lr=1.0, **options):
        defaults = dict(lr=lr, rcond=1e-6, backend="auto", precision="double",
                        eigensolver="auto")
        defaults.update(options)
        _physgrad._hig_params(self.rule, defaults)  # physgrad.Error before anything is made
        self._previous = None  # the last step's spectrum: the next auto choices follow it
        self.last_info = None
        super().__init__(params, defaults)

    def add_param_group(self, param_group):
        given = {k: v for k, v in param_group.items() if k != "params"}
        merged = dict(self.defaults, **given)
        _physgrad._hig_params(self.rule, merged)
        for name in _SHARED:
            if self.param_groups and merged[name] != self.param_groups[0][name]:
                raise _physgrad.Error(
                    f"{self.rule}: {name} {merged[name]!r} differs from the first group's "
                    f"{self.param_groups[0][name]!r}: every group shares the one inversion")
        super().add_param_group(param_group)

    def _trainable(self):
        return [(group, p) for group in self.param_groups for p in trainable(group["params"])]

    @torch.no_grad()
    def step(self, closure):
        with torch.enable_grad():
            loss, jacobian, dl_dy = closure()
        pairs = self._trainable()
        count = sum(p.numel() for _, p in pairs)
        if jacobian.shape[-1] != count:
            raise _physgrad.Error(
                f"{self.rule}: the Jacobian has {jacobian.shape[-1]} columns, the trainable "
                f"parameters {count} entries (make J over the same parameters: "
                "jacobian_closure(..., params=...)); nothing was changed")
        delta, info = self.jacobian_step(jacobian, dl_dy, lr=1.0)
        self._apply(pairs, delta)
        self._previous = info["state"]
        self.last_info = info
        return loss

    def _apply(self, pairs, delta, lr=None):
        """θ ← θ + lr·Δθ for every trainable parameter (lr: its group's, unless given), in its
        dtype and device, or nothing: a value that would not be finite refuses the step
        (physgrad.NumericalError)."""
        updated, offset = [], 0
        for index, (group, p) in enumerate(pairs):
            n = p.numel()
            rate = group["lr"] if lr is None else lr
            step = torch.from_numpy(delta[offset:offset + n]).view(p.shape)
            value = (p.detach().to("cpu", torch.float64) + rate * step).to(p.dtype)
            if not bool(torch.isfinite(value).all()):
                raise _physgrad.NumericalError(
                    f"{self.rule}: the step would make parameter {index} ({tuple(p.shape)}, "
                    f"{p.dtype}) non-finite (lr {rate:g}, max |Δθ| "
                    f"{float(step.abs().max()):.3g}); nothing was changed")
            updated.append(value)
            offset += n
        for (_, p), value in zip(pairs, updated):
            p.copy_(value.to(p.device))

    def jacobian_step(self, jacobian, dl_dy, lr=None):
        """(Δθ, info) for J and dL/dy (tensors or arrays) without changing the parameters; Δθ
        is float64 over the trainable parameters in order, scaled by `lr` (default: the first
        group's)."""
        group = self.param_groups[0]
        j = torch.as_tensor(jacobian).detach()
        if j.dtype not in (torch.float64, torch.float32):
            j = j.to(torch.float32)
        j = j.to("cpu").contiguous()
        g = torch.as_tensor(dl_dy).detach().reshape(-1).to("cpu", torch.float64)
        return _physgrad.jacobian_step(
            j.numpy(), g.numpy(), lr=group["lr"] if lr is None else lr,
            kappa=0.5 if self.rule == "hig" else 1.0, rcond=group["rcond"],
            backend=group["backend"], precision=group["precision"],
            eigensolver=group["eigensolver"],
            previous=self.last_info["state"] if self.last_info else self._previous)

    @torch.no_grad()
    def find_lr(self, closure, evaluate, candidates=(0.25, 0.5, 1.0, 2.0, 4.0, 8.0)):
        """Chooses the step size: computes the step direction once (one closure), evaluates
        evaluate() (the loss, no graph needed) at θ + lr·Δθ for every candidate, sets the best lr
        in every group and leaves θ unchanged. Returns {lr: loss}."""
        with torch.enable_grad():
            _, jacobian, dl_dy = closure()
        pairs = self._trainable()
        delta, _ = self.jacobian_step(jacobian, dl_dy, lr=1.0)
        saved = [p.detach().clone() for _, p in pairs]
        losses = {}
        try:
            for lr in candidates:
                try:
                    self._apply(pairs, delta, lr=lr)
                    losses[lr] = float(evaluate())
                except _physgrad.NumericalError:
                    losses[lr] = float("inf")
                for (_, p), value in zip(pairs, saved):
                    p.copy_(value)
        finally:
            for (_, p), value in zip(pairs, saved):
                p.copy_(value)
        finite = {lr: loss for lr, loss in losses.items() if loss == loss}  # NaN left out
        best = min(finite, key=finite.get) if finite else None
        if best is None or finite[best] == float("inf"):
            raise _physgrad.NumericalError(f"{self.rule}: find_lr: no candidate step size gives "
                                           f"a finite loss ({losses})")
        for group in self.param_groups:
            group["lr"] = best
        return losses

    def state_dict(self):
        state = super().state_dict()
        state["physgrad"] = {"previous": self._previous}
        return state

    def load_state_dict(self, state_dict):
        state_dict = dict(state_dict)
        extra = state_dict.pop("physgrad", {})
        for group in state_dict.get("param_groups", []):
            _physgrad._hig_params(self.rule, {k: v for k, v in group.items() if k != "params"})
        super().load_state_dict(state_dict)
        self._previous = extra.get("previous")


class HIG(_JacobianRule):
    """Half-inverse gradients: Δθ = −lr·J^{−½}·∂L/∂y (truncated at rcond·σ_max)."""

    rule = "hig"


class GN(_JacobianRule):
    """Gauss-Newton: Δθ = −lr·J⁺·∂L/∂y (truncated at rcond·σ_max)."""

    rule = "gn"


def jacobian_closure(model, simulate, loss_fn, inputs, targets, chunk=None, params=None,
                     mode="auto"):
    """A closure for HIG/GN.step: y = simulate(model(inputs)), loss = loss_fn(y, targets) (the
    batch mean), J by per_sample_jacobian over `params` (default: the model's trainable
    parameters; give the optimizer's when it holds fewer) in the parameters' dtype, ∂loss/∂y by
    autograd."""

    def closure():
        with torch.no_grad():
            y = simulate(model(inputs))
        y = y.detach().requires_grad_(True)
        loss = loss_fn(y, targets)
        (dl_dy,) = torch.autograd.grad(loss, y)
        jacobian = per_sample_jacobian(model, simulate, inputs, chunk=chunk, params=params,
                                       mode=mode)
        return loss.detach(), jacobian, dl_dy

    return closure
