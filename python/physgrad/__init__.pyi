# Type stubs of the package physgrad (__init__.py).
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._physgrad import (Error as Error, MinimizeResult as MinimizeResult,
                        NumericalError as NumericalError, blas_core as blas_core,
                        blas_core_note as blas_core_note, direct_rules as direct_rules,
                        jacobian_step as jacobian_step, learning_rules as learning_rules,
                        LearningExperiment as LearningExperiment,
                        open_metrics as open_metrics, open_summary as open_summary,
                        reference_step as reference_step, rule_defaults as rule_defaults)
from ._results import (Experiment as Experiment, LocalInverseResult as LocalInverseResult,
                       RunOutcome as RunOutcome)

__version__: str

class BlasCoreWarning(RuntimeWarning): ...

Bounds = Union[Tuple[Optional[npt.ArrayLike], Optional[npt.ArrayLike]],
               List[Tuple[Optional[float], Optional[float]]], Any]

def minimize(sim: Any, x0: npt.ArrayLike, rule: str = ..., *,
             target: Optional[npt.ArrayLike] = ..., loss_weight: float = ...,
             bounds: Optional[Bounds] = ..., x_scale: Optional[npt.ArrayLike] = ...,
             max_iterations: int = ..., loss_tolerance: float = ...,
             relative_loss_tolerance: float = ..., gradient_tolerance: float = ...,
             function_tolerance: float = ..., parameter_tolerance: float = ...,
             max_evaluations: int = ..., max_seconds: float = ..., max_history: int = ...,
             max_history_values: int = ..., differences: str = ...,
             callback: Optional[Callable[[int, float, npt.NDArray[np.float64]],
                                         Optional[bool]]] = ...,
             **rule_options: Union[float, int, str]) -> MinimizeResult: ...
def local_inverse(sim: Any, y: npt.ArrayLike, x0: npt.ArrayLike, method: str = ..., *,
                  tolerance: float = ..., max_iterations: int = ...,
                  relative_tolerance: float = ..., function_tolerance: float = ...,
                  rcond: float = ..., bounds: Optional[Bounds] = ...) -> LocalInverseResult: ...
def experiments() -> List[Experiment]: ...
def run_experiment(name: str, options: Optional[Dict[str, Any]] = ..., out: str = ...,
                   progress: Union[bool, None, Callable[[str], Any]] = ...,
                   experiments: Optional[List[LearningExperiment]] = ...) -> RunOutcome: ...
def resume_experiment(folder: str,
                      progress: Union[bool, None, Callable[[str], Any]] = ...,
                      experiments: Optional[List[LearningExperiment]] = ...) -> RunOutcome: ...
def write_index(folder: str,
                experiments: Optional[List[LearningExperiment]] = ...) -> Dict[str, Any]: ...
