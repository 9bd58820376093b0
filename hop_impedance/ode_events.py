"""Terminal events for ``scipy.integrate.solve_ivp`` (no science here; the simulator and the strict generator
share it so neither sets attributes on plain functions)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass
class TerminalEvent:
    """A terminal ``solve_ivp`` event: ``fun(t, y)`` with the ``terminal`` and ``direction`` scipy reads.

    ``direction`` as scipy's: -1 only zero crossings from positive to negative, +1 the reverse, 0 both.
    """

    fun: Callable[[float, np.ndarray], float]
    direction: float = 0.0
    terminal: bool = True

    def __call__(self, t: float, y: np.ndarray) -> float:
        return self.fun(t, y)
