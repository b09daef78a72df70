"""physgrad's learning rules as torch optimizers (docs/python.md).

HIG and GN step with Δθ = −lr·J^{−κ}·∂L/∂y (κ = ½ and 1), computed by the library (HigUpdate on
a MappedJacobian) from the per-sample Jacobian J of shape (B, m, P) and ∂L/∂y of shape (B, m).
KFAC/KFACHIG (Kronecker factors per Linear/Conv layer) and LanczosGN/LanczosHIG (matrix-free
Lanczos) step with the library's structured rules from structured_closure's batches.
SIP trains on proxy targets x̃ = P⁻¹(y + η(y* − y); x) found by the library's local inverse, with
torch's Adam on ½‖f(input; θ) − x̃‖². Jacobians come from batched autodiff (_jacobian.py).
"""

from ._jacobian import (choose_chunk, choose_mode, memory_budget, per_sample_jacobian,
                        sample_jacobian)
from ._kfac import KFAC, KFACHIG
from ._lanczos import LanczosGN, LanczosHIG
from ._optim import GN, HIG, jacobian_closure
from ._sip import SIP, TorchSimulator, sip_closure
from ._structured import StructuredBatch, structured_closure

__all__ = ["HIG", "GN", "KFAC", "KFACHIG", "LanczosGN", "LanczosHIG", "structured_closure",
           "StructuredBatch", "SIP", "TorchSimulator", "jacobian_closure", "sip_closure",
           "per_sample_jacobian", "sample_jacobian", "memory_budget", "choose_chunk",
           "choose_mode"]
