# Type stubs of physgrad.torch (__init__.py): the optimizers with the keywords they take. Every
# default (`...`) is the library's catalogue's for that rule: physgrad.rule_defaults("hig").
from typing import Any, Callable, Dict, Iterable, Optional, Sequence, Tuple, Union

import torch

Params = Union[Iterable[torch.Tensor], Iterable[Dict[str, Any]]]
JacobianClosure = Callable[[], Tuple[torch.Tensor, torch.Tensor, torch.Tensor]]
SipClosure = Callable[[], Tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]]

class HIG(torch.optim.Optimizer):
    last_info: Optional[Dict[str, Any]]
    def __init__(self, params: Params, lr: float = ..., kappa: float = ...,
                 rcond: float = ..., backend: str = ..., precision: str = ...,
                 eigensolver: str = ...) -> None: ...
    def step(self, closure: JacobianClosure) -> torch.Tensor: ...  # type: ignore[override]
    def jacobian_step(self, jacobian: Any, dl_dy: Any,
                      lr: Optional[float] = ...) -> Tuple[Any, Dict[str, Any]]: ...
    def find_lr(self, closure: JacobianClosure, evaluate: Callable[[], Any],
                candidates: Sequence[float] = ...) -> Dict[float, float]: ...

class GN(HIG):
    def __init__(self, params: Params, lr: float = ..., kappa: float = ...,
                 rcond: float = ..., backend: str = ..., precision: str = ...,
                 eigensolver: str = ...) -> None: ...

class TorchSimulator:
    def __init__(self, simulate: Callable[[torch.Tensor], torch.Tensor],
                 inverse: Optional[Callable[..., torch.Tensor]] = ...,
                 name: str = ..., mode: str = ..., dtype: torch.dtype = ...,
                 device: Any = ...) -> None: ...

class SIP(torch.optim.Adam):
    last_info: Optional[Dict[str, Any]]
    def __init__(self, params: Params, simulator: Any, lr: float = ..., *,
                 y_step: float = ..., beta1: float = ..., beta2: float = ...,
                 epsilon: float = ..., inverse: str = ..., inverse_tolerance: float = ...,
                 inverse_iterations: int = ..., inverse_relative_tolerance: float = ...,
                 inverse_function_tolerance: float = ...,
                 inverse_rcond: float = ...) -> None: ...
    def step(self, closure: SipClosure) -> torch.Tensor: ...  # type: ignore[override]
    def proxy_targets(self, x: torch.Tensor, y: torch.Tensor,
                      y_star: torch.Tensor) -> Tuple[torch.Tensor, Dict[str, Any]]: ...

def jacobian_closure(model: torch.nn.Module, simulate: Callable[[torch.Tensor], torch.Tensor],
                     loss_fn: Callable[[torch.Tensor, torch.Tensor], torch.Tensor],
                     inputs: torch.Tensor, targets: torch.Tensor, chunk: Optional[int] = ...,
                     params: Optional[Sequence[torch.Tensor]] = ...,
                     mode: str = ...) -> JacobianClosure: ...
def sip_closure(model: torch.nn.Module, simulate: Callable[[torch.Tensor], torch.Tensor],
                inputs: torch.Tensor, targets: torch.Tensor) -> SipClosure: ...
def per_sample_jacobian(model: torch.nn.Module, simulate: Callable[[torch.Tensor], torch.Tensor],
                        inputs: torch.Tensor, chunk: Optional[int] = ...,
                        dtype: Optional[torch.dtype] = ...,
                        params: Optional[Sequence[torch.Tensor]] = ...,
                        mode: str = ...) -> torch.Tensor: ...
def sample_jacobian(simulate: Callable[[torch.Tensor], torch.Tensor], x: torch.Tensor,
                    mode: str = ..., outputs: Optional[int] = ...) -> torch.Tensor: ...
def memory_budget(device: Any = ...) -> int: ...
def choose_chunk(batch: int, bytes_per_sample: float, device: Any = ...) -> int: ...
def choose_mode(inputs: int, outputs: int) -> str: ...
