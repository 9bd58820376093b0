"""Pooled impedance coefficient over the last N accepted stances (issue 21: what a controller should latch).

One stance's coefficient is noisy (hip k1 scatters by SD up to 73 % from
stance to stance with realistic noise); its fit reports a standard error
(:class:`~hop_impedance.impedance.stance_fit.JointImpedanceFit.std_errors`).
The pooled value over the last ``N`` accepted stances is the inverse-variance
weighted mean, the fixed-effect estimate of a coefficient assumed constant
over those stances:

    w_i = 1 / SE_i^2,   pooled = sum(w_i c_i) / sum(w_i),   SE_pooled = 1 / sqrt(sum(w_i)).

Choices (the seed papers say nothing about pooling):

- Only stances whose fit was accepted (``fit.ok``) and whose coefficient and
  standard error are finite with SE > 0 enter. A coefficient held at a bound by
  the constraints (no finite SE) or absent from the fitted structure does not.
- ``SE_pooled`` is the fixed-effect standard error: right when the stances
  differ only by noise. When the coefficient itself drifts from stance to
  stance (fatigue, a changed task) the scatter exceeds the SEs; the pooled
  estimate reports that as ``chi2_per_dof`` (Cochran's Q / (n - 1), near 1 when
  the SEs explain the scatter) so a consumer can tell, instead of widening the
  SE silently.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    from hop_impedance.impedance.stance_fit import JointImpedanceFit


@dataclass(frozen=True)
class PooledEstimate:
    """Inverse-variance pooled coefficient.

    Attributes
    ----------
    value : float
        Pooled coefficient (NaN when no stance qualified).
    std_error : float
        Its standard error ``1/sqrt(sum 1/SE_i^2)`` (NaN when no stance qualified).
    n_stances : int
        Stances that entered.
    chi2_per_dof : float
        Cochran's Q / (n - 1); NaN for fewer than two stances.
    """

    value: float
    std_error: float
    n_stances: int
    chi2_per_dof: float


def pooled_coefficient(values: ArrayLike, std_errors: ArrayLike) -> PooledEstimate:
    """Inverse-variance weighted mean of ``values`` with standard errors ``std_errors`` (see module docstring).

    Entries whose value or SE is not finite, or whose SE is not positive, are left out.
    """
    c = np.asarray(values, float).ravel()
    se = np.asarray(std_errors, float).ravel()
    if c.shape != se.shape:
        raise ValueError(f"values and std_errors differ in length: {c.size} vs {se.size}")
    ok = np.isfinite(c) & np.isfinite(se) & (se > 0)
    c, se = c[ok], se[ok]
    if c.size == 0:
        return PooledEstimate(float("nan"), float("nan"), 0, float("nan"))
    w = 1.0 / se**2
    value = float(np.sum(w * c) / np.sum(w))
    q = float(np.sum(w * (c - value) ** 2))
    return PooledEstimate(value, float(1.0 / np.sqrt(np.sum(w))), int(c.size), q / (c.size - 1) if c.size > 1 else float("nan"))


class StancePool:
    """The last ``n`` accepted fits of one joint, pooled per coefficient on request.

    ``add`` ignores rejected fits (they are not "accepted stances"), so the
    window always holds up to ``n`` accepted ones.
    """

    def __init__(self, n: int) -> None:
        if int(n) < 1:
            raise ValueError(f"the pool needs n >= 1 stances, got {n}")
        self._fits: deque[JointImpedanceFit] = deque(maxlen=int(n))

    def __len__(self) -> int:
        return len(self._fits)

    def add(self, fit: JointImpedanceFit) -> bool:
        """Add a :class:`JointImpedanceFit`; True if it was accepted into the pool."""
        if not fit.ok:
            return False
        self._fits.append(fit)
        return True

    def clear(self) -> None:
        """Forget every stance (e.g. when the subject changes)."""
        self._fits.clear()

    def withdraw(self, fit: JointImpedanceFit) -> bool:
        """Take out a fit added earlier (its stance's take-off was withdrawn); True if it was in the pool."""
        for i, f in enumerate(self._fits):
            if f is fit:
                del self._fits[i]
                return True
        return False

    def estimate(self, term: str) -> PooledEstimate:
        """Pooled ``term`` (e.g. ``"k0"``) over the pool's fits that carry it."""
        values = [f.coefficients.get(term, np.nan) for f in self._fits]
        errors = [f.std_errors.get(term, np.nan) for f in self._fits]
        return pooled_coefficient(values, errors)
