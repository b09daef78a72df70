"""HIG and Gauss-Newton as torch optimizers: Δθ = −lr·J^{−κ}·∂L/∂y (κ = ½ and 1 unless given)
by HigUpdate.

They follow torch.optim: param groups (each with its own lr; the one inversion shares κ, rcond,
backend, precision and eigensolver), frozen parameters (requires_grad=False) skipped, options
checked when the optimizer or a group is made and before every step, state_dict() round trip,
real parameters of any dtype and device. The step runs where the library runs (CPU, double); nothing is written until the
whole update is known to be finite in every parameter's own dtype.
"""

import math

import torch

from .. import _physgrad
from ._jacobian import per_sample_jacobian, trainable


def _numbers(tensor, who, name):
    """`tensor` (a torch tensor) for the library, or physgrad.Error naming what it is."""
    if not isinstance(tensor, torch.Tensor):
        raise _physgrad.Error(f"{who}: {name} is a {type(tensor).__name__}, expected a torch "
                              "tensor")
    if tensor.is_complex():
        raise _physgrad.Error(f"{who}: {name} is complex ({tensor.dtype}); the step is real")
    return tensor


class _LibraryRule(torch.optim.Optimizer):
    """The base of the torch optimizers whose step the library computes: its options are checked
    by the library (`_check_options`) when the optimizer is made, when a group is added, before
    every step and when a state is loaded; options in `shared` must agree between the groups
    (one computation serves them all); parameters are real tensors of any dtype and device, the
    frozen ones (requires_grad=False) skipped; nothing is written until the whole update is
    finite in every parameter's own dtype. A rule class gives `rule` (its catalogue id),
    `shared` and `_check_options(options)`, and steps with `_apply`.
    """

    rule = ""
    shared = ()

    def __init__(self, params, defaults):
        params = list(params)
        if not params:
            raise _physgrad.Error(f"{self.rule}: no parameters given (an exhausted generator? "
                                  "model.parameters() can be read once)")
        self._check_options(defaults)  # physgrad.Error before anything is made
        super().__init__(params, defaults)

    def _check_options(self, options):
        raise NotImplementedError

    def _check_group(self, group, first):
        """The group's options (as the library checks them) and parameters; `first`: the first
        group, whose shared options this one must have."""
        options = {k: v for k, v in group.items() if k != "params"}
        self._check_options(options)
        for name in self.shared:
            if first is not None and options[name] != first[name]:
                raise _physgrad.Error(
                    f"{self.rule}: {name} {options[name]!r} differs from the first group's "
                    f"{first[name]!r}: every group shares the one inversion")
        for index, p in enumerate(group["params"]):
            _numbers(p, self.rule, f"parameter {index}")

    def add_param_group(self, param_group):
        params = param_group["params"]
        params = [params] if isinstance(params, torch.Tensor) else list(params)
        param_group = dict(param_group, params=params)  # a generator is read once, here
        merged = dict(self.defaults, **param_group)
        self._check_group(merged, self.param_groups[0] if self.param_groups else None)
        super().add_param_group(param_group)

    def _check_groups(self):
        """Every group as it is now (its values may have been changed since it was added)."""
        for group in self.param_groups:
            self._check_group(group, self.param_groups[0])

    def _trainable(self):
        pairs = [(group, p) for group in self.param_groups for p in trainable(group["params"])]
        if not pairs:
            raise _physgrad.Error(f"{self.rule}: no parameter trains (all have "
                                  "requires_grad=False); nothing was changed")
        return pairs

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

    def _check_loaded_groups(self, groups):
        for group in groups:
            options = {k: v for k, v in group.items() if k != "params"}
            self._check_options(options)
            for name in self.shared:
                if options.get(name) != groups[0].get(name):
                    raise _physgrad.Error(
                        f"{self.rule}: load_state_dict: {name} {options.get(name)!r} differs "
                        f"from the first group's {groups[0].get(name)!r}: every group shares "
                        "the one inversion")


def _finite_tree(value):
    """Whether every number in a nested dict/list of a saved state is finite."""
    if isinstance(value, dict):
        return all(_finite_tree(v) for v in value.values())
    if isinstance(value, (list, tuple)):
        return all(_finite_tree(v) for v in value)
    if isinstance(value, float):
        return math.isfinite(value)
    return True


class _JacobianRule(_LibraryRule):
    """Δθ = −lr·J^{−κ}·∂L/∂y over the trainable parameters of all groups, in their order.

    step(closure): closure() returns (loss, J, dL_dy), J of shape (B, m, P) over the trainable
    parameters (P their entries, in order, each flattened) and dL_dy of shape (B, m),
    ∂(mean loss)/∂y; jacobian_closure makes one. A float64 or float32 CPU J that is
    C-contiguous is read where it lies.
    """

    rule = "hig"
    # Options every group must share: the step inverts one Jacobian over all of them.
    shared = ("kappa", "rcond", "backend", "precision", "eigensolver")

    def __init__(self, params, options):
        # options: the rule's keywords; one it does not take (**unknown of HIG and GN) is
        # refused by the check with the options it does take.
        self._previous = None  # the last step's spectrum: the next auto choices follow it
        self.last_info = None
        super().__init__(params, options)

    def _check_options(self, options):
        _physgrad._hig_params(self.rule, options)

    def _directions(self, closure, who):
        """The closure's (loss, J, dL/dy), checked against the trainable parameters."""
        if closure is None:
            raise _physgrad.Error(f"{self.rule}: {who} needs a closure returning (loss, J, dL_dy)"
                                  "; make one with physgrad.torch.jacobian_closure(...)")
        self._check_groups()
        with torch.enable_grad():
            returned = closure()
        if not isinstance(returned, (tuple, list)) or len(returned) != 3:
            shown = type(returned).__name__ + (f" of {len(returned)}" if isinstance(
                returned, (tuple, list)) else "")
            raise _physgrad.Error(
                f"{self.rule}: the closure returned a {shown}, expected (loss, J, dL_dy) as "
                "physgrad.torch.jacobian_closure(...) makes (an LBFGS closure returns the loss "
                "alone; SIP's closure returns four items)")
        loss, jacobian, dl_dy = returned
        _numbers(jacobian, self.rule, "J")
        _numbers(dl_dy, self.rule, "dL_dy")
        pairs = self._trainable()
        count = sum(p.numel() for _, p in pairs)
        if jacobian.dim() != 3:
            raise _physgrad.Error(f"{self.rule}: the Jacobian has shape {tuple(jacobian.shape)}"
                                  ", expected (B, m, P); nothing was changed")
        if jacobian.shape[-1] != count:
            raise _physgrad.Error(
                f"{self.rule}: the Jacobian has {jacobian.shape[-1]} columns, the trainable "
                f"parameters {count} entries (make J over the same parameters: "
                "jacobian_closure(..., params=...)); nothing was changed")
        return loss, jacobian, dl_dy, pairs

    @torch.no_grad()
    def step(self, closure=None):
        loss, jacobian, dl_dy, pairs = self._directions(closure, "step")
        delta, info = self.jacobian_step(jacobian, dl_dy, lr=1.0)
        self._apply(pairs, delta)
        self._previous = info["state"]
        self.last_info = info
        return loss

    def jacobian_step(self, jacobian, dl_dy, lr=None):
        """(Δθ, info) for J and dL/dy (tensors or arrays) without changing the parameters; Δθ
        is float64 over the trainable parameters in order, scaled by `lr` (default: the first
        group's)."""
        group = self.param_groups[0]
        j = torch.as_tensor(jacobian).detach()
        if j.is_complex():
            raise _physgrad.Error(f"{self.rule}: J is complex ({j.dtype}); the step is real")
        if j.dtype not in (torch.float64, torch.float32):
            j = j.to(torch.float32)
        j = j.to("cpu").contiguous()
        g = torch.as_tensor(dl_dy).detach().reshape(-1).to("cpu", torch.float64)
        return _physgrad.jacobian_step(
            j.numpy(), g.numpy(), lr=group["lr"] if lr is None else lr, kappa=group["kappa"],
            rcond=group["rcond"], backend=group["backend"], precision=group["precision"],
            eigensolver=group["eigensolver"],
            previous=self.last_info["state"] if self.last_info else self._previous)

    @torch.no_grad()
    def find_lr(self, closure, evaluate, candidates=(0.25, 0.5, 1.0, 2.0, 4.0, 8.0)):
        """Chooses the step size: computes the step direction once (one closure), evaluates
        evaluate() (the loss, no graph needed) before the step and at θ + lr·Δθ for every
        candidate, sets in every group the candidate with the lowest loss among those that lower
        the loss, and leaves θ unchanged. Returns {lr: loss}, with the loss before the step at
        lr 0; physgrad.NumericalError when no candidate lowers it."""
        _, jacobian, dl_dy, pairs = self._directions(closure, "find_lr")
        delta, _ = self.jacobian_step(jacobian, dl_dy, lr=1.0)
        saved = [p.detach().clone() for _, p in pairs]
        losses = {0: float(evaluate())}
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
        lower = {lr: loss for lr, loss in losses.items() if lr != 0 and loss < losses[0]}
        if not lower:
            raise _physgrad.NumericalError(
                f"{self.rule}: find_lr: no candidate step size lowers the loss "
                f"{losses[0]:.6g} ({losses}); the parameters are unchanged")
        best = min(lower, key=lower.get)
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
        groups = state_dict.get("param_groups", [])
        self._check_loaded_groups(groups)
        previous = extra.get("previous") if isinstance(extra, dict) else None
        if not _finite_tree(previous):
            raise _physgrad.Error(f"{self.rule}: load_state_dict: the saved spectrum "
                                  "('physgrad' → 'previous') holds a value that is not finite")
        super().load_state_dict(state_dict)
        self._previous = previous


# The keyword defaults of HIG and GN: the library's catalogue's (physgrad.rule_defaults), read
# once here.
_HIG = _physgrad.rule_defaults("hig")
_GN = _physgrad.rule_defaults("gn")


class HIG(_JacobianRule):
    """Half-inverse gradients: Δθ = −lr·J^{−κ}·∂L/∂y, κ = ½ by default (truncated at
    rcond·σ_max); the defaults are the library's hig's."""

    rule = "hig"

    def __init__(self, params, lr=_HIG["lr"], kappa=_HIG["kappa"], rcond=_HIG["rcond"],
                 backend=_HIG["backend"], precision=_HIG["precision"],
                 eigensolver=_HIG["eigensolver"], **unknown):
        super().__init__(params, dict(lr=lr, kappa=kappa, rcond=rcond, backend=backend,
                                      precision=precision, eigensolver=eigensolver, **unknown))


class GN(_JacobianRule):
    """Gauss-Newton: Δθ = −lr·J^{−κ}·∂L/∂y, κ = 1 (J⁺) by default (truncated at
    rcond·σ_max); the defaults are the library's gn's."""

    rule = "gn"

    def __init__(self, params, lr=_GN["lr"], kappa=_GN["kappa"], rcond=_GN["rcond"],
                 backend=_GN["backend"], precision=_GN["precision"],
                 eigensolver=_GN["eigensolver"], **unknown):
        super().__init__(params, dict(lr=lr, kappa=kappa, rcond=rcond, backend=backend,
                                      precision=precision, eigensolver=eigensolver, **unknown))


def jacobian_closure(model, simulate, loss_fn, inputs, targets, chunk=None, params=None,
                     mode="auto"):
    """A closure for HIG/GN.step: y = simulate(model(inputs)), loss = loss_fn(y, targets) (the
    batch mean), J by per_sample_jacobian over `params` (default: the model's trainable
    parameters; give the optimizer's when it holds fewer) in the parameters' dtype, ∂loss/∂y by
    autograd."""
    _numbers(inputs, "jacobian_closure", "inputs")
    _numbers(targets, "jacobian_closure", "targets")

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
