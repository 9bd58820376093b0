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
from scipy.optimize import brentq


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


def lossless(law: Ground) -> Ground:
    """The same law without damping (for energy bookkeeping); with a pad in series the surface's damper (the pad is
    elastic) is removed and the pad kept."""
    if isinstance(law, PaddedGround):
        return PaddedGround(_undamped(law.surface), law.pad)
    return _undamped(law)


def _undamped(law: GroundLaw) -> GroundLaw:
    return GroundLaw(law.name + "_lossless", law.stiffness, law.exponent, 0.0, law.damping_exponent)


@dataclass(frozen=True)
class PaddedGround:
    """A compliant pad (shoe sole and the forefoot's soft tissue) in series with a surface law (issue 17).

    The seed's subjects hopped in shoes ("All the jumpers were provided with the same manufacturer and type of
    shoes", seed 000, Methods) on a force plate; our contact point is the toe tip. The pad is an elastic law
    ``F = k_p d^n_p`` (``pad``, a :class:`GroundLaw` whose damping must be 0) carrying the same force as the
    surface's spring ``F = k s^n`` (massless interface): the toe's penetration ``p = s + d`` is shared so that
    both forces are equal. A stiffening pad (``n_p > 1``) makes the contact soft at small force and stiff at
    large force, so the leg in series with it is soft early in stance and the ground force peaks more, while
    the joint laws are unchanged.

    Choice (documented, tested in test/simulation/test_sim_ground_pad.py): the surface's damper acts on the
    rate of the whole penetration, ``c s^m p'`` with ``s`` the surface's share (``m`` the surface's damping
    exponent, so a Hunt-Crossley surface's damping still starts from zero); the pad's own hysteresis is lumped
    into it. Without surface damping the contact is conservative: its stored energy is the two springs' at the
    common force, ``F s / (n + 1) + F d / (n_p + 1)``.
    """

    surface: GroundLaw
    pad: GroundLaw

    def __post_init__(self) -> None:
        if self.pad.damping_n_s_m != 0.0:
            raise ValueError(f"pad {self.pad.name!r}: an elastic pad needs damping 0 (the surface's damper carries "
                             f"the contact's losses), got {self.pad.damping_n_s_m}")

    @property
    def name(self) -> str:
        """The surface's name (the trial's surface; the pad is stated in :meth:`to_dict`)."""
        return self.surface.name

    def split_m(self, penetration_m: float) -> tuple[float, float]:
        """Surface share ``s`` and pad compression ``d`` (m) of a penetration ``p = s + d >= 0`` (equal forces)."""
        p = max(float(penetration_m), 0.0)
        if p == 0.0:
            return 0.0, 0.0
        ks, ns, kp, npad = self.surface.stiffness, self.surface.exponent, self.pad.stiffness, self.pad.exponent

        def pad_share(s: float) -> float:  # pad compression carrying the surface spring's force at share s
            return (ks * s**ns / kp) ** (1.0 / npad)

        s = brentq(lambda s: s + pad_share(s) - p, 0.0, p, xtol=1e-15, rtol=4 * np.finfo(float).eps)
        return s, p - s

    def elastic_force_n(self, penetration_m: float) -> float:
        """The series springs' common force (N) at a penetration (m)."""
        s, _ = self.split_m(penetration_m)
        return self.surface.stiffness * s**self.surface.exponent

    def unclipped_force_n(self, y_m: float, ydot_m_s: float) -> float:
        """Law value (N) as :meth:`GroundLaw.unclipped_force_n`: series springs minus the surface's damper."""
        s, _ = self.split_m(-y_m)
        return self.surface.unclipped_force_n(-s, ydot_m_s)  # the surface at its share s of the penetration

    def force_n(self, y_m: float, ydot_m_s: float) -> float:
        """Vertical force on the toe (N), never negative, zero out of contact."""
        if y_m >= 0.0:
            return 0.0
        return max(self.unclipped_force_n(y_m, ydot_m_s), 0.0)

    def stored_energy_j(self, y_m: np.ndarray | float) -> np.ndarray | float:
        """Elastic energy of surface and pad at the toe's height(s) ``y`` (J)."""
        pen = np.maximum(-np.asarray(y_m, float), 0.0)
        out = np.zeros(pen.shape)
        for i, p in np.ndenumerate(pen):
            s, d = self.split_m(float(p))
            force = self.surface.stiffness * s**self.surface.exponent
            out[i] = force * s / (self.surface.exponent + 1.0) + force * d / (self.pad.exponent + 1.0)
        return out if out.ndim else float(out)

    def to_dict(self) -> dict:
        """Plain parameters for the truth file: the surface's and the pad's, in series."""
        return {**self.surface.to_dict(), "pad_in_series": self.pad.to_dict()}


#: What the foot meets: a surface law, or one with a shoe pad in series (:func:`with_pad`).
Ground = GroundLaw | PaddedGround


def with_pad(law: Ground, pad: GroundLaw | None) -> Ground:
    """``law`` with ``pad`` in series (:class:`PaddedGround`); ``pad`` None: ``law`` itself."""
    if pad is None:
        return law
    base = law.surface if isinstance(law, PaddedGround) else law
    return PaddedGround(base, pad)
