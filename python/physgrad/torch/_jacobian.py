"""Jacobians by batched autodiff: forward or reverse mode by shape, the chunk chosen from memory.

per_sample_jacobian: J[i, k, :] = ∂y_ik/∂θ of a network through a simulator, by functorch's vmap
over samples of jacrev (m backward passes per sample, for P ≥ m) or jacfwd (P forward-mode
passes, for P < m). sample_jacobian: ∂P/∂x of a batched torch function at one point, with the
function's own batch dimension standing in for vmap: n copies of x carrying the unit tangents
through one forward-mode pass (n ≤ m), or m copies through one pass and one backward (n > m).
"""

import os

import functorch
import torch
from torch.autograd import forward_ad
from torch.nn.utils import stateless

from .. import _physgrad

# The memory one chunk of a Jacobian may take (bytes), unless PHYSGRAD_JACOBIAN_MEMORY says.
_DEFAULT_BUDGET = 512 << 20


def memory_budget(device=None):
    """The bytes one Jacobian chunk may take: PHYSGRAD_JACOBIAN_MEMORY if set, else a quarter of
    the memory free now (on a GPU: that device's free memory), at most 512 MiB."""
    given = os.environ.get("PHYSGRAD_JACOBIAN_MEMORY")
    if given:
        return max(1, int(float(given)))
    free = None
    if device is not None and torch.device(device).type == "cuda":
        free = torch.cuda.mem_get_info(device)[0]
    else:
        try:
            with open("/proc/meminfo", encoding="ascii") as info:
                for line in info:
                    if line.startswith("MemAvailable:"):
                        free = int(line.split()[1]) * 1024
        except OSError:
            pass
    return _DEFAULT_BUDGET if free is None else max(1 << 20, min(_DEFAULT_BUDGET, free // 4))


def choose_chunk(batch, bytes_per_sample, device=None):
    """Samples per chunk: as many as fit the memory budget (all of them, usually), at least 1."""
    return int(max(1, min(batch, memory_budget(device) // max(1, bytes_per_sample))))


def choose_mode(inputs, outputs):
    """"fwd" when forward mode needs fewer passes (inputs < outputs), else "rev"."""
    return "fwd" if inputs < outputs else "rev"


def trainable(params):
    """The parameters that train (requires_grad), in order; frozen ones are left out."""
    return [p for p in params if p.requires_grad]


def per_sample_jacobian(model, simulate, inputs, chunk=None, dtype=None, params=None,
                        mode="auto"):
    """J[i, k, :] = ∂y_ik/∂θ for y_i = simulate(model(inputs[i])), one (B, m, P) tensor.

    θ: `params` (default: the model's trainable parameters), in order, each flattened; frozen
    parameters have no columns. mode: "rev" (vmap of jacrev), "fwd" (vmap of jacfwd) or "auto"
    (forward mode when P < m). chunk: samples per vmap call; None chooses the largest that fits
    the memory budget (memory_budget()). dtype: J's dtype (default: the parameters').
    """
    if not isinstance(inputs, torch.Tensor):
        raise _physgrad.Error(f"per_sample_jacobian: inputs is a {type(inputs).__name__}, "
                              "expected a torch tensor (torch.as_tensor(inputs))")
    batch_norms = [name for name, module in model.named_modules()
                   if isinstance(module, torch.nn.modules.batchnorm._BatchNorm) and
                   module.training]
    if batch_norms:
        raise _physgrad.Error(
            f"per_sample_jacobian: {batch_norms[0] or 'the model'} is a BatchNorm in training "
            "mode, which mixes the samples of a batch and has no per-sample Jacobian (call "
            "model.eval(), or use LayerNorm or GroupNorm)")
    named = dict(model.named_parameters())
    chosen = trainable(model.parameters()) if params is None else list(params)
    by_id = {id(p): name for name, p in named.items()}
    missing = [i for i, p in enumerate(chosen) if id(p) not in by_id]
    if missing:
        raise ValueError(f"physgrad.torch: parameter {missing[0]} is not a parameter of the model")
    names = [by_id[id(p)] for p in chosen]
    values = tuple(p.detach() for p in chosen)

    def output(theta, x):
        return simulate(stateless.functional_call(model, dict(zip(names, theta)),
                                                  (x.unsqueeze(0),))).squeeze(0)

    batch = inputs.shape[0]
    total = sum(v.numel() for v in values)
    with torch.no_grad():
        m = output(values, inputs[0]).numel()
    if mode == "auto":
        mode = choose_mode(total, m)
    if mode not in ("fwd", "rev"):
        raise ValueError(f"physgrad.torch: mode {mode!r} is not 'auto', 'fwd' or 'rev'")
    differentiate = functorch.jacfwd if mode == "fwd" else functorch.jacrev
    jac = functorch.vmap(differentiate(output), in_dims=(None, 0))
    dtype = dtype or (values[0].dtype if values else torch.float32)
    item = torch.empty((), dtype=values[0].dtype if values else dtype).element_size()
    if chunk is None:
        # J's rows, the per-output parameter gradients of the vmapped backward and the copy
        # into J: about three m × P blocks a sample.
        chunk = choose_chunk(batch, 3 * m * total * item, inputs.device)
    chunk = max(1, int(chunk))
    jacobian = torch.empty((batch, m, total), dtype=dtype, device=inputs.device)
    for start in range(0, batch, chunk):
        parts = jac(values, inputs[start:start + chunk])
        stop = start + parts[0].shape[0]
        column = 0
        for part in parts:  # written in place: no concatenated copy
            width = part[0, 0].numel()
            jacobian[start:stop, :, column:column + width] = part.reshape(stop - start, m, width)
            column += width
    return jacobian


def sample_jacobian(simulate, x, mode="auto", outputs=None):
    """∂simulate/∂x at one point x (n,) as (m, n), simulate mapping (B, n) to (B, m) sample by
    sample. Forward mode sends n copies of x with the unit tangents through one forward-mode
    pass; reverse mode m copies through one pass, then one backward of Σₖ y[k, k]. Both rest on
    the samples of a batch being independent. mode "auto": forward when n ≤ m (falling back to
    reverse when an operation has no forward-mode derivative)."""
    n = x.numel()
    if outputs is None:
        with torch.no_grad():
            outputs = simulate(x.reshape(1, n)).numel()
    if mode == "auto":
        if n <= outputs:
            try:
                return _forward_mode(simulate, x, n)
            except (NotImplementedError, RuntimeError) as error:
                if "forward" not in str(error).lower():
                    raise
        return _reverse_mode(simulate, x, n, outputs)
    if mode == "fwd":
        return _forward_mode(simulate, x, n)
    if mode == "rev":
        return _reverse_mode(simulate, x, n, outputs)
    raise ValueError(f"physgrad.torch: mode {mode!r} is not 'auto', 'fwd' or 'rev'")


def _forward_mode(simulate, x, n):
    with forward_ad.dual_level():
        copies = forward_ad.make_dual(x.reshape(1, n).expand(n, n).clone(),
                                      torch.eye(n, dtype=x.dtype, device=x.device))
        tangent = forward_ad.unpack_dual(simulate(copies)).tangent
    if tangent is None:  # the output does not depend on x
        with torch.no_grad():
            return torch.zeros(simulate(x.reshape(1, n)).numel(), n, dtype=x.dtype)
    return tangent.reshape(n, -1).transpose(0, 1)


def _reverse_mode(simulate, x, n, m):
    with torch.enable_grad():
        copies = x.reshape(1, n).expand(m, n).clone().requires_grad_(True)
        y = simulate(copies).reshape(m, m)
        (rows,) = torch.autograd.grad(y.diagonal().sum(), copies, allow_unused=True)
    return torch.zeros(m, n, dtype=x.dtype) if rows is None else rows
