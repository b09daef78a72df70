"""SIP as a torch optimizer, and TorchSimulator: a simulator object made of torch functions.

SIP trains on proxy targets x̃ = P⁻¹(y + η(y* − y); x) in the network's output space, found by the
library's local inverse on the simulator object, with torch's Adam on ½‖f(input; θ) − x̃‖².
"""

import torch

from .. import _physgrad
from ._jacobian import sample_jacobian


class TorchSimulator:
    """A simulator object for the library (minimize(), local_inverse(), SIP) made of torch
    functions on batches: simulate(x) maps (B, n) to (B, m), sample by sample, differentiable in
    x; inverse(y, x0) maps (B, m) and (B, n) to the preimage (B, n) near x0.

    The library calls forward, vjp, jacobian and inverse on one sample (1-D numpy arrays) and
    forward_batch and inverse_batch on a batch (one sample a row): SIP's analytic targets take
    one batched inverse and one batched forward a step. jacobian(x) is ∂P/∂x by autodiff, the
    batch dimension standing in for vmap (physgrad.torch.sample_jacobian): forward mode when
    n ≤ m, reverse otherwise, or as `mode` says ("fwd", "rev"). Computed in `dtype` (float64) on
    `device`.
    """

    def __init__(self, simulate, inverse=None, name="torch simulator", mode="auto",
                 dtype=torch.float64, device="cpu"):
        self.simulate = simulate
        self.name = name
        self.mode = mode
        self.dtype, self.device = dtype, torch.device(device)
        self._output_dim = None
        if inverse is not None:
            self._inverse = inverse
            self.inverse = self._inverse_one
            self.inverse_batch = self._inverse_rows

    def _tensor(self, array):
        tensor = torch.as_tensor(array)  # the array's memory, for a float64 NumPy array
        if tensor.dtype == self.dtype and tensor.device == self.device:
            return tensor
        return tensor.to(self.device, self.dtype)

    @staticmethod
    def _numpy(tensor):
        tensor = tensor.detach()
        if tensor.dtype != torch.float64 or tensor.device.type != "cpu":
            tensor = tensor.to("cpu", torch.float64)
        return tensor.numpy()

    def forward(self, x):
        with torch.no_grad():
            return self._numpy(self.simulate(self._tensor(x).unsqueeze(0))).reshape(-1)

    def forward_batch(self, x):
        with torch.no_grad():
            y = self.simulate(self._tensor(x))
        return self._numpy(y.reshape(x.shape[0], -1))

    def vjp(self, x, gy):
        with torch.enable_grad():
            x = self._tensor(x).unsqueeze(0).requires_grad_(True)
            y = self.simulate(x)
            (gx,) = torch.autograd.grad(y, x, self._tensor(gy).view(y.shape))
        return self._numpy(gx).reshape(-1)

    def jacobian(self, x):
        x = self._tensor(x)
        if self._output_dim is None:  # m, asked once: the choice of mode needs it
            with torch.no_grad():
                self._output_dim = self.simulate(x.reshape(1, -1)).numel()
        return self._numpy(sample_jacobian(self.simulate, x, self.mode, outputs=self._output_dim))

    def _inverse_one(self, y, x0):
        return self._inverse_rows(y.reshape(1, -1), x0.reshape(1, -1))

    def _inverse_rows(self, y, x0):
        with torch.no_grad():
            x = self._inverse(self._tensor(y), self._tensor(x0))
        return self._numpy(x)  # its shape checked by the library


class SIP(torch.optim.Adam):
    """Scale-invariant physics training: per sample x̃ = P⁻¹(y + η(y* − y); x) by the library's
    local inverse on `simulator`, then one step of torch's Adam on the proxy loss
    mean ½‖x − x̃‖² with x̃ held constant.

    simulator: an object as minimize() takes it (forward(x), optional inverse(y, x0), vjp,
    jacobian, time_reversal, on 1-D numpy arrays; forward_batch and inverse_batch on (B, ·)
    arrays let the analytic targets of a batch be made in one call each), e.g. a
    TorchSimulator. options: sip's options of the rule catalogue, by name: y_step (η), beta1,
    beta2, epsilon (Adam's), inverse ("auto", "analytic", "time_reversal", "lbfgs", "ig") and
    inverse_tolerance, inverse_iterations, inverse_relative_tolerance,
    inverse_function_tolerance, inverse_rcond. A name sip does not take or a value out of range
    raises physgrad.Error.

    step(closure): closure() returns (loss, x, y, y_star): x = f(inputs; θ) of shape (B, n) with
    its graph to the parameters, y = P(x) and the targets y* of shape (B, m); sip_closure makes
    one. The y-space step η(y* − y) is the Newton step of the L2 loss ½‖y − y*‖².
    """

    def __init__(self, params, simulator, lr=_physgrad.rule_defaults("sip")["lr"], **options):
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
    def step(self, closure=None):
        if closure is None:
            raise _physgrad.Error("sip: step needs a closure returning (loss, x, y, y_star); "
                                  "make one with physgrad.torch.sip_closure(...)")
        with torch.enable_grad():
            returned = closure()
        if not isinstance(returned, (tuple, list)) or len(returned) != 4:
            shown = type(returned).__name__ + (f" of {len(returned)}" if isinstance(
                returned, (tuple, list)) else "")
            raise _physgrad.Error(
                f"sip: the closure returned a {shown}, expected (loss, x, y, y_star) as "
                "physgrad.torch.sip_closure(...) makes (HIG's and GN's closure returns three "
                "items: (loss, J, dL_dy))")
        loss, x, y, y_star = returned
        for name, value in (("x", x), ("y", y), ("y_star", y_star)):
            if not isinstance(value, torch.Tensor) or value.dim() != 2:
                raise _physgrad.Error(f"sip: the closure's {name} is not a (B, ·) torch tensor "
                                      f"({type(value).__name__})")
        x_tilde, info = self.proxy_targets(x, y, y_star)
        params = [p for group in self.param_groups for p in group["params"] if p.requires_grad]
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
    for name, value in (("inputs", inputs), ("targets", targets)):
        if not isinstance(value, torch.Tensor):
            raise _physgrad.Error(f"sip_closure: {name} is a {type(value).__name__}, expected a "
                                  "torch tensor (torch.as_tensor(...))")

    def closure():
        x = model(inputs)
        with torch.no_grad():
            y = simulate(x)
            loss = 0.5 * ((y - targets) ** 2).sum(dim=1).mean()
        return loss, x, y, targets

    return closure
