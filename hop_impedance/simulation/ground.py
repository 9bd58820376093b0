"""Vertical foot-surface force laws (seed 001, van der Krogt et al. 2009).

The surface acts on the toe only. ``y`` is the toe's vertical position
relative to the undeformed surface (m, z up), so ``y < 0`` is penetration:

    Fz = k |y|^n - c |y|^m dy/dt    for y < 0,      Fz = 0 otherwise.

with damping exponent ``m = 0`` for seed 001's laws (plain viscous damping)
and ``m = n`` (Hunt-Crossley) for the rigid surface, whose force must start
from zero at touchdown instead of jumping by ``c |y'|``.

Seed 001's laws: soft ``Fz = 7.5e4 |y|^1.4 - 68.4 y'`` and hard
``Fz = 3.1e6 |y|^2 - 186.3 y'`` (N, m, m/s).

Choices (documented here, tested in ``test/simulation/test_sim_laws.py`` and ``test_sim_dynamics.py``)
---------------------------------------------------------------------
- The surface is massless and never pulls: contact ends (take-off) at the
  first instant the law's force reaches zero while the toe rises, even if the
  damped surface has not yet recovered to ``y = 0``; the surface is taken to
  recover before the next touchdown (flight lasts >100 ms).
- Horizontal contact is a kinematic no-slip constraint (toe x fixed during
  stance); the horizontal force is the constraint force, not a law here.
- "rigid" is the same law made very stiff (k = 1e8 N/m^1.5, n = 1.5, Hertz-like)
  with Hunt-Crossley damping (m = n, c = 1.0 s/m x k) so that the force rises
  from zero without a jump and the toe does not bounce; it is integrated by the
  same stiff-capable solver (LSODA); penetration at 3 body weights is ~1 mm.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np


@dataclass(frozen=True)
class GroundLaw:
    """``Fz = k |y|^n - c |y|^m y'`` for ``y < 0`` (N).

    Attributes
    ----------
    name : str
    stiffness : float
        k (N / m^n).
    exponent : float
        n (dimensionless), > 0.
    damping_n_s_m : float
        c (N s / m^(1+m)), >= 0.
    damping_exponent : float
        m, 0 for plain viscous damping (seed 001), ``exponent`` for Hunt-Crossley.
    """

    name: str
    stiffness: float
    exponent: float
    damping_n_s_m: float
    damping_exponent: float = 0.0

    def __post_init__(self) -> None:
        if not (self.stiffness > 0 and self.exponent > 0 and self.damping_n_s_m >= 0):
            raise ValueError(
                f"ground law {self.name!r}: need k > 0, n > 0, c >= 0; got "
                f"k={self.stiffness}, n={self.exponent}, c={self.damping_n_s_m}"
            )

    def unclipped_force_n(self, y_m: float, ydot_m_s: float) -> float:
        """Law value ``k p^n - c p^m y'`` with ``p = max(-y, 0)`` (N); negative means the surface would pull."""
        pen = max(-y_m, 0.0)
        damping = self.damping_n_s_m * (pen**self.damping_exponent if self.damping_exponent else 1.0)
        return self.stiffness * pen**self.exponent - damping * ydot_m_s

    def force_n(self, y_m: float, ydot_m_s: float) -> float:
        """Vertical force on the toe (N), never negative, zero out of contact."""
        if y_m >= 0.0:
            return 0.0
        return max(self.unclipped_force_n(y_m, ydot_m_s), 0.0)

    def stored_energy_j(self, y_m: np.ndarray | float) -> np.ndarray | float:
        """Elastic energy of the surface ``k |y|^(n+1) / (n+1)`` (J) for ``y < 0``."""
        pen = np.maximum(-np.asarray(y_m, float), 0.0)
        return self.stiffness * pen ** (self.exponent + 1.0) / (self.exponent + 1.0)

    def to_dict(self) -> dict:
        """Plain parameters for the truth file."""
        return asdict(self)


SOFT = GroundLaw("soft", 7.5e4, 1.4, 68.4)
HARD = GroundLaw("hard", 3.1e6, 2.0, 186.3)
RIGID = GroundLaw("rigid", 1.0e8, 1.5, 1.0e8, 1.5)

SURFACES: dict[str, GroundLaw] = {law.name: law for law in (SOFT, HARD, RIGID)}


def surface(name: str) -> GroundLaw:
    """A named surface: ``soft``, ``hard`` (seed 001) or ``rigid``."""
    try:
        return SURFACES[name]
    except KeyError:
        raise ValueError(f"unknown surface {name!r}; expected one of {sorted(SURFACES)}") from None


def lossless(law: GroundLaw) -> GroundLaw:
    """The same law without damping (for energy bookkeeping)."""
    return GroundLaw(law.name + "_lossless", law.stiffness, law.exponent, 0.0, law.damping_exponent)
