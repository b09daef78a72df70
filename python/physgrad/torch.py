"""physgrad's learning rules as torch optimizers (docs/python.md).

HIG and GN step with Δθ = −lr·J^{−κ}·∂L/∂y (κ = ½ and 1), computed by the library
(HigUpdate on a MappedJacobian) from the per-sample Jacobian J of shape (B, m, P) and ∂L/∂y of
shape (B, m). A float64 tensor is read where it lies, never copied; float32 is converted once.

SIP trains on proxy targets x̃ = P⁻¹(y + η(y* − y); x) in the network's output space, found by
the library's local inverse (the simulator's own, its time reversal, or a numerical one), with
torch's Adam on ½‖f(input; θ) − x̃‖².
"""

import functorch
import torch
from torch.nn.utils import stateless

from . import _physgrad


def per_sample_jacobian(model, simulate, inputs, chunk=None, dtype=None):
    """J[i, k, :] = ∂y_ik/∂θ for y_i = simulate(model(inputs[i])), as one (B, m, P) tensor.

    Built with functorch (vmap over samples of jacrev in θ), `chunk` samples at a time so that
    the autograd memory is bounded by the chunk; each chunk is written into the one J.
    """
    names = [n for n, _ in model.named_parameters()]
    values = tuple(p.detach() for _, p in model.named_parameters())

    def output(theta, x):
        params = dict(zip(names, theta))
        return simulate(stateless.functional_call(model, params, (x.unsqueeze(0),))).squeeze(0)

    jac = functorch.vmap(functorch.jacrev(output), in_dims=(None, 0))
    batch = inputs.shape[0]
    chunk = batch if chunk is None else max(1, int(chunk))
    total = sum(v.numel() for v in values)
    jacobian = None
    for start in range(0, batch, chunk):
        parts = jac(values, inputs[start:start + chunk])
        flat = torch.cat([part.reshape(part.shape[0], part.shape[1], -1) for part in parts], dim=2)
        if jacobian is None:
            jacobian = torch.empty((batch, flat.shape[1], total),
                                   dtype=dtype or flat.dtype)
        jacobian[start:start + flat.shape[0]] = flat
    return jacobian


class _JacobianRule(torch.optim.Optimizer):
    """Δθ = −lr·J^{−κ}·∂L/∂y over the parameters, in the order given.

    step(closure): closure() returns (loss, J, dL_dy) with J of shape (B, m, P) (P the number
    of parameters, in their order, each flattened) and dL_dy of shape (B, m), ∂(mean loss)/∂y.
    J is handed to the library without a copy when it is a C-contiguous float64 CPU tensor.
    """

    kappa = 0.5

    def __init__(self, params, lr=1.0, rcond=1e-6, backend="auto", precision="double",
                 eigensolver="auto"):
        super().__init__(params, dict(lr=lr, rcond=rcond, backend=backend, precision=precision,
                                      eigensolver=eigensolver))
        self.last_info = None

    @torch.no_grad()
    def step(self, closure):
        with torch.enable_grad():
            loss, jacobian, dl_dy = closure()
        group = self.param_groups[0]
        if len(self.param_groups) != 1:
            raise ValueError("physgrad.torch: one parameter group only")
        delta, info = self.jacobian_step(jacobian, dl_dy, group)
        offset = 0
        for p in group["params"]:
            n = p.numel()
            p.add_(torch.from_numpy(delta[offset:offset + n]).view_as(p).to(p.dtype))
            offset += n
        if offset != delta.shape[0]:
            raise ValueError(f"physgrad.torch: the Jacobian has {delta.shape[0]} columns, "
                             f"the parameters {offset} entries")
        self.last_info = info
        return loss

    def jacobian_step(self, jacobian, dl_dy, group=None):
        """(Δθ, info) for J and dL/dy (tensors or arrays) without changing the parameters."""
        group = group or self.param_groups[0]
        j = jacobian.detach()
        if j.device.type != "cpu":
            raise ValueError("physgrad.torch: the Jacobian must be on the CPU")
        g = dl_dy.detach().reshape(-1).to(torch.float64).numpy()
        # The last step's spectrum guides the auto choice of precision and eigensolver.
        previous = self.last_info["state"] if self.last_info else None
        return _physgrad.jacobian_step(j.numpy(), g, lr=group["lr"], kappa=self.kappa,
                                       rcond=group["rcond"], backend=group["backend"],
                                       precision=group["precision"],
                                       eigensolver=group["eigensolver"], previous=previous)


class HIG(_JacobianRule):
    """Half-inverse gradients: Δθ = −lr·J^{−½}·∂L/∂y (truncated at rcond·σ_max)."""

    kappa = 0.5


class GN(_JacobianRule):
    """Gauss-Newton: Δθ = −lr·J⁺·∂L/∂y (truncated at rcond·σ_max)."""

    kappa = 1.0


def jacobian_closure(model, simulate, loss_fn, inputs, targets, chunk=None):
    """A closure for HIG/GN.step: y = simulate(model(inputs)), loss = loss_fn(y, targets) (the
    batch mean), J from per_sample_jacobian (in chunks) and ∂loss/∂y by autograd."""

    def closure():
        with torch.no_grad():
            y = simulate(model(inputs))
        y = y.detach().requires_grad_(True)
        loss = loss_fn(y, targets)
        (dl_dy,) = torch.autograd.grad(loss, y)
        jacobian = per_sample_jacobian(model, simulate, inputs, chunk=chunk,
                                       dtype=torch.float64)
        return loss.detach(), jacobian, dl_dy

    return closure


class TorchSimulator:
    """A simulator object for the library (forward, vjp and optionally inverse on 1-D numpy
    arrays, as minimize() and SIP take) made of torch functions on batches.

    simulate(x) maps (B, n) to (B, m) and is differentiable in x (its VJP serves the numerical
    local inverses); inverse(y, x0) maps (B, m) and (B, n) to the preimage (B, n) near x0. Both
    are called with B = 1 on float64 tensors.
    """

    def __init__(self, simulate, inverse=None, name="torch simulator"):
        self.simulate = simulate
        self.name = name
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


class SIP(torch.optim.Adam):
    """Scale-invariant physics training: per sample x̃ = P⁻¹(y + η(y* − y); x) by the library's
    local inverse on `simulator`, then one step of torch's Adam on the proxy loss
    mean ½‖x − x̃‖² with x̃ held constant.

    simulator: an object as minimize() takes it (forward(x), optional inverse(y, x0), vjp,
    jacobian, time_reversal, on 1-D numpy arrays), e.g. a TorchSimulator. options: sip's options
    of the rule catalogue, by name: y_step (η), beta1, beta2, epsilon (Adam's), inverse ("auto",
    "analytic", "time_reversal", "lbfgs", "ig") and inverse_tolerance, inverse_iterations,
    inverse_relative_tolerance, inverse_function_tolerance, inverse_rcond. A name sip does not
    take or a value out of range raises physgrad.Error.

    step(closure): closure() returns (loss, x, y, y_star): x = f(inputs; θ) of shape (B, n) with
    its graph to the parameters, y = P(x) and the targets y* of shape (B, m); sip_closure makes
    one. The y-space step η(y* − y) is the Newton step of the L2 loss ½‖y − y*‖².
    """

    def __init__(self, params, simulator, lr=1e-3, **options):
        checked = _physgrad._sip_params(dict(options, lr=lr))
        super().__init__(params, lr=checked["lr"], betas=(checked["beta1"], checked["beta2"]),
                         eps=checked["epsilon"])
        self.simulator = simulator
        self.options = dict(options)
        self.last_info = None

    def proxy_targets(self, x, y, y_star):
        """(x̃, info) for the batch without a step: x̃ of x's shape, dtype and device; info the
        library's residual ‖P(x̃) − (y + Δy)‖ and converged per sample, iterations, evaluations
        and the simulator's counts, summed over the batch."""
        arrays = [t.detach().to("cpu", torch.float64).numpy() for t in (x, y, y_star)]
        info = _physgrad._sip_targets(self.simulator, *arrays, self.options)
        x_tilde = torch.from_numpy(info.pop("x")).to(x.device, x.dtype)
        return x_tilde, info

    @torch.no_grad()
    def step(self, closure):
        with torch.enable_grad():
            loss, x, y, y_star = closure()
        x_tilde, info = self.proxy_targets(x, y, y_star)
        params = [p for group in self.param_groups for p in group["params"]]
        with torch.enable_grad():
            proxy = 0.5 * ((x - x_tilde) ** 2).sum(dim=1).mean()
            grads = torch.autograd.grad(proxy, params, allow_unused=True)
        for p, g in zip(params, grads):
            p.grad = g
        super().step()
        info["proxy_loss"] = float(proxy)
        self.last_info = info
        return loss


def sip_closure(model, simulate, inputs, targets):
    """A closure for SIP.step: x = model(inputs) with its graph, y = simulate(x) without one,
    loss = ½‖y − targets‖² (the batch mean)."""

    def closure():
        x = model(inputs)
        with torch.no_grad():
            y = simulate(x)
            loss = 0.5 * ((y - targets) ** 2).sum(dim=1).mean()
        return loss, x, y, targets

    return closure
