# The simulators the tests share, written as a physgrad user writes them in Python.
import numpy as np
import pytest


class ScaledToy:
    """P(x) = (x₁, α·x₂): the scaled toy of the scaled-toy experiment, with its exact parts."""

    def __init__(self, alpha, analytic=True):
        self.alpha = float(alpha)
        self.name = f"scaled toy α={alpha:g}"
        if analytic:
            self.jacobian = lambda x: np.diag([1.0, self.alpha])
            self.vjp = lambda x, gy: np.array([gy[0], self.alpha * gy[1]])
            self.inverse = lambda y, x0: np.array([y[0], y[1] / self.alpha])

    def forward(self, x):
        return np.array([x[0], self.alpha * x[1]])


@pytest.fixture
def scaled_toy():
    return ScaledToy
