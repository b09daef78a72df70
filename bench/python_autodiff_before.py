"""The previous code paths of physgrad.torch, kept for bench/python_autodiff.py to measure the
new ones against in the same run: the per-sample Jacobian with the chunk given by the caller and
J widened to float64, its closure, and a TorchSimulator without jacobian() or batched calls (the
library then makes J from m VJPs and asks for SIP's targets one sample at a time)."""

import functorch
import torch
from torch.nn.utils import stateless

import two_oscillators as osc


def legacy_per_sample_jacobian(model, simulate, inputs, chunk):
    names = [n for n, _ in model.named_parameters()]
    values = tuple(p.detach() for _, p in model.named_parameters())

    def output(theta, x):
        params = dict(zip(names, theta))
        return simulate(stateless.functional_call(model, params, (x.unsqueeze(0),))).squeeze(0)

    jac = functorch.vmap(functorch.jacrev(output), in_dims=(None, 0))
    batch = inputs.shape[0]
    total = sum(v.numel() for v in values)
    jacobian = None
    for start in range(0, batch, chunk):
        parts = jac(values, inputs[start:start + chunk])
        flat = torch.cat([part.reshape(part.shape[0], part.shape[1], -1) for part in parts], dim=2)
        if jacobian is None:
            jacobian = torch.empty((batch, flat.shape[1], total), dtype=torch.float64)
        jacobian[start:start + flat.shape[0]] = flat
    return jacobian


def legacy_closure(model, inputs, targets, chunk):
    def closure():
        with torch.no_grad():
            y = osc.simulate(model(inputs))
        y = y.detach().requires_grad_(True)
        loss = osc.loss_fn(y, targets)
        (dl_dy,) = torch.autograd.grad(loss, y)
        return loss.detach(), legacy_per_sample_jacobian(model, osc.simulate, inputs, chunk), dl_dy

    return closure


class LegacySimulator:
    """forward, vjp and inverse one sample at a time, in float64."""

    name = "legacy torch simulator"

    def __init__(self, simulate, inverse=None):
        self.simulate = simulate
        if inverse is not None:
            self.inverse = lambda y, x0: _one_sample(inverse, y, x0)

    def forward(self, x):
        with torch.no_grad():
            return _one_sample(self.simulate, x)

    def vjp(self, x, gy):
        with torch.enable_grad():
            x = torch.from_numpy(x).unsqueeze(0).requires_grad_(True)
            y = self.simulate(x)
            (gx,) = torch.autograd.grad(y, x, torch.from_numpy(gy).reshape(y.shape).to(y.dtype))
        return gx.detach().squeeze(0).to(torch.float64).numpy()


def _one_sample(function, *arrays):
    out = function(*(torch.from_numpy(a).unsqueeze(0) for a in arrays))
    return out.detach().squeeze(0).to(torch.float64).numpy()
