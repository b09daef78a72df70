"""What the structured torch rules share (_kfac.py, _lanczos.py): the closure that gives the
batch, the rule options read from the library's own, and the param-group habits of HIG and GN.

structured_closure(...)() returns a StructuredBatch: the loss (batch mean), ∂loss/∂y of shape
(B, m) and forward(values=None), which evaluates y = simulate(model(inputs)) with a graph, with
the model's parameters or with `values` ({name: tensor}) in their place.
"""

import collections
import math

import torch
from torch.nn.utils import stateless

from .. import _physgrad
from ._jacobian import trainable

StructuredBatch = collections.namedtuple("StructuredBatch", "loss dl_dy forward")


def structured_closure(model, simulate, loss_fn, inputs, targets):
    """A closure for KFAC, KFACHIG, LanczosGN and LanczosHIG: y = simulate(model(inputs)),
    loss = loss_fn(y, targets) (the batch mean), ∂loss/∂y by autograd, and y's forward pass."""

    def forward(values=None):
        out = model(inputs) if values is None else stateless.functional_call(model, values,
                                                                             (inputs,))
        return simulate(out)

    def closure():
        with torch.no_grad():
            y = forward()
        y = y.detach().requires_grad_(True)
        loss = loss_fn(y, targets)
        (dl_dy,) = torch.autograd.grad(loss, y)
        return StructuredBatch(loss.detach(), dl_dy.reshape(y.shape[0], -1), forward)

    return closure


def check_batch(rule, batch):
    """Refuses (physgrad.NumericalError) a non-finite loss or ∂loss/∂y, before any change."""
    if not math.isfinite(float(batch.loss)):
        raise _physgrad.NumericalError(f"{rule}: the loss is {float(batch.loss)}; nothing was "
                                       "changed")
    if not bool(torch.isfinite(batch.dl_dy).all()):
        raise _physgrad.NumericalError(f"{rule}: ∂L/∂y has a non-finite entry; nothing was "
                                       "changed")


class StructuredRule(torch.optim.Optimizer):
    """torch.optim habits over one of the library's structured rules (`rule`, its options and
    defaults as the library's descriptors give them): param groups with their own lr, the other
    options shared, frozen parameters skipped, options checked before anything is made."""

    rule = ""

    def __init__(self, params, model, lr=None, **options):
        given = dict(options)  # the others: `rule`'s defaults in the library's catalogue
        if lr is not None:
            given["lr"] = lr
        defaults = dict(_physgrad._structured_params(self.rule, given))  # Error before anything
        self._model = model
        self._names = {id(p): name for name, p in model.named_parameters()}
        super().__init__(params, defaults)
        missing = [p for _, p in self._trainable() if id(p) not in self._names]
        if missing:
            raise _physgrad.Error(f"{self.rule}: a parameter of shape {tuple(missing[0].shape)} "
                                  "is not a parameter of the model")

    def add_param_group(self, param_group):
        given = {k: v for k, v in param_group.items() if k != "params"}
        merged = dict(self.defaults, **given)
        _physgrad._structured_params(self.rule, merged)
        for name in self.defaults:
            if name != "lr" and self.param_groups and merged[name] != self.param_groups[0][name]:
                raise _physgrad.Error(
                    f"{self.rule}: {name} {merged[name]!r} differs from the first group's "
                    f"{self.param_groups[0][name]!r}: every group shares the one rule")
        super().add_param_group(param_group)

    def _trainable(self):
        return [(group, p) for group in self.param_groups for p in trainable(group["params"])]

    def _option(self, name):
        return self.param_groups[0][name]

    def _apply(self, pairs, deltas):
        """θ ← θ + lr·Δθ for every trainable parameter (its group's lr), in its own dtype and
        device, or nothing: a value that would not be finite refuses the step."""
        updated = []
        for index, ((group, p), delta) in enumerate(zip(pairs, deltas)):
            value = (p.detach().to(torch.float64) + group["lr"] * delta.to(p.device)).to(p.dtype)
            if not bool(torch.isfinite(value).all()):
                raise _physgrad.NumericalError(
                    f"{self.rule}: the step would make parameter {index} ({tuple(p.shape)}, "
                    f"{p.dtype}) non-finite (lr {group['lr']:g}); nothing was changed")
            updated.append(value)
        for (_, p), value in zip(pairs, updated):
            p.copy_(value)

    def load_state_dict(self, state_dict):
        for group in state_dict.get("param_groups", []):
            _physgrad._structured_params(self.rule,
                                         {k: v for k, v in group.items() if k != "params"})
        super().load_state_dict(state_dict)
