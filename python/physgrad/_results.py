"""Typed results with the dict view kept: the attributes of a result are also its keys."""

from typing import Any, Dict, Iterator, List, NamedTuple, Optional

import numpy as np


class _DictView(dict):
    """A dict whose keys are also attributes: result["x"] is result.x; len(), iteration (over
    the keys), keys(), items(), get(), `in` and json.dumps as for a dict."""

    _fields: tuple = ()

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(f"{type(self).__name__} has no attribute {name!r}") from None

    def __setattr__(self, name, value):
        self[name] = value

    def as_dict(self) -> Dict[str, Any]:
        return dict(self)


class _KeyedTuple:
    """For a NamedTuple: e["name"] is e.name, keys(), items(), get() and `in` over the names;
    e[0] and iteration as for the tuple."""

    _fields: tuple = ()

    def __getitem__(self, key):
        if isinstance(key, str):
            if key not in self._fields:
                raise KeyError(key)
            return getattr(self, key)
        return tuple.__getitem__(self, key)

    def __contains__(self, key):
        return key in self._fields

    def keys(self):
        return list(self._fields)

    def items(self):
        return [(k, getattr(self, k)) for k in self._fields]

    def get(self, key, default=None):
        return getattr(self, key) if key in self._fields else default

    def as_dict(self) -> Dict[str, Any]:
        return dict(self.items())


class LocalInverseResult(_DictView):
    """What local_inverse() returned: the preimage x and how well it meets P(x) = y."""

    _fields = ("x", "residual", "iterations", "evaluations", "counts", "converged")

    def __init__(self, x: np.ndarray, residual: float, iterations: int, evaluations: int,
                 counts: Dict[str, int], converged: bool):
        self.x, self.residual, self.iterations = x, residual, iterations
        self.evaluations, self.counts, self.converged = evaluations, counts, converged

    def __repr__(self):
        return (f"LocalInverseResult(residual={self.residual:.3g}, converged={self.converged}, "
                f"iterations={self.iterations})")


class RunOutcome(_DictView):
    """What run_experiment() and resume_experiment() returned."""

    _fields = ("folder", "finished", "report", "stopped", "summary")

    def __init__(self, folder: str, finished: bool, report: str, stopped: str,
                 summary: Optional[Dict[str, Any]]):
        self.folder, self.finished, self.report = folder, finished, report
        self.stopped, self.summary = stopped, summary

    def __repr__(self):
        return f"RunOutcome(folder={self.folder!r}, finished={self.finished})"


class Experiment(_KeyedTuple, NamedTuple("_Experiment", [("name", str), ("description", str)])):
    """An experiment: `for name, description in experiments()`, or e.name, or e["name"]."""

    _fields = ("name", "description")

    def __iter__(self) -> Iterator[str]:
        return tuple.__iter__(self)


def _experiments(listed: List[Dict[str, str]]) -> List[Experiment]:
    return [Experiment(d["name"], d["description"]) for d in listed]
