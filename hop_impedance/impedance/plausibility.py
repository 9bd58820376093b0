"""When a fit may reach a controller: the physical plausibility rule of ``/impedance/controller``.

A joint's entry of the controller feed is ``valid`` only if its stance passed
the input checks (:mod:`hop_impedance.input_checks`), its fit was accepted, and
the fit is physically credible (:func:`controller_rejection`):

- R^2 >= ``min_r_squared`` (0.5);
- K(rho) >= 0 over the whole stance (a spring that pushes the wrong way is no
  stiffness a prosthesis should copy), up to floating-point round-off
  (:data:`STIFFNESS_ROUND_OFF`): where the QP holds K on its K >= 0 bound (the
  knee at take-off on the seed-like recordings), K = k0 + k1 (rho - rho0) is two
  terms of ~10^2 N m/rad cancelling and comes out as +-1e-13, which is the bound
  itself, not a spring pushing the wrong way;
- the equivalent linear stiffness k_eq > 0 and damping b_eq >= 0, where a
  b_eq in ``[-damping_tolerance, 0)`` is published as 0 (valid) and a more
  negative one makes the joint invalid. Choice: the seed found damping
  negligible, and the ordinary least-squares b_eq of such joints scatters
  around 0 (-1.79 to -0.15 N m s/rad at the ankle and knee of
  sim_2p20hz_hard, whose law has b0 = 0.5); without the tolerance nearly
  every stance of the bundled recordings would be invalid. What reaches the controller as valid always
  has b_eq >= 0 (:func:`controller_damping`).
- k0 within a factor ``k0_factor`` (5) of the seed's Table 2 k0 for that
  joint, scaled by body mass (``k0_ref * mass / 54.8 kg``, the seed subjects'
  mean mass);
- |k1| at most ``k1_factor`` (5) times its mass-scaled Table 2 value.

Which Table 2 row: the seed measured 1.53, 1.87 and 2.20 Hz and k0, k1 grow
with frequency. The seed is silent on other frequencies; we take the row
nearest to the stance's hop frequency, and when the frequency is unknown
(first stance) the widest band the three rows allow (lowest k0 / 5 to highest
k0 x 5, |k1| up to 5 x the highest k1). The bounds are configurable
(:class:`PlausibilityBounds`, node parameters of ``impedance_estimator``);
the defaults live here and nowhere else.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from hop_impedance.seed_tables import FREQUENCIES_HZ, SUBJECT_MASS_KG, eq10_k0_k1, nearest_frequency_hz

if TYPE_CHECKING:
    from hop_impedance.impedance.stance_fit import JointImpedanceFit

#: Mean body mass of the seed's subjects (kg): "body mass 54.8 (SD, 4.8) kg" (:mod:`hop_impedance.seed_tables`).
SEED_BODY_MASS_KG = SUBJECT_MASS_KG


#: |K| below this (N m/rad) is K = 0 (module docstring): ~1e8 x the round-off measured on the bound
#: (1.7e-13 on recordings/sim_2p20hz_hard's knee) and ~1e-8 of any joint's k0, so no real negative
#: stiffness passes.
STIFFNESS_ROUND_OFF = 1e-5


@dataclass(frozen=True)
class PlausibilityBounds:
    """Bounds of :func:`controller_rejection` (module docstring)."""

    min_r_squared: float = 0.5
    k0_factor: float = 5.0
    k1_factor: float = 5.0
    damping_tolerance: float = 2.0


def table2_band(
    joint: str, hop_frequency_hz: float | None, body_mass_kg: float, bounds: PlausibilityBounds
) -> tuple[float, float, float]:
    """``(k0_low, k0_high, k1_max)`` in N m/rad for ``joint``, mass-scaled (module docstring)."""
    scale = body_mass_kg / SEED_BODY_MASS_KG
    rows = list(FREQUENCIES_HZ)
    if hop_frequency_hz is not None and math.isfinite(hop_frequency_hz):
        rows = [nearest_frequency_hz(hop_frequency_hz)]
    k0 = [eq10_k0_k1(f, joint)[0] * scale for f in rows]
    k1 = [eq10_k0_k1(f, joint)[1] * scale for f in rows]
    return min(k0) / bounds.k0_factor, max(k0) * bounds.k0_factor, max(k1) * bounds.k1_factor


def controller_rejection(
    joint: str,
    fit: JointImpedanceFit,
    stiffness_eq: float,
    damping_eq: float,
    hop_frequency_hz: float | None,
    body_mass_kg: float,
    bounds: PlausibilityBounds | None = None,
) -> str | None:
    """Why an accepted fit must not reach a controller as valid, or None (module docstring).

    Parameters
    ----------
    joint : str
        ``ankle``, ``knee`` or ``hip``.
    fit : JointImpedanceFit
        An accepted fit (``fit.ok``); a rejected one returns its own reason.
    stiffness_eq, damping_eq : float
        Equivalent linear impedance of the stance (N m/rad, N m s/rad).
    hop_frequency_hz : float or None
    body_mass_kg : float
    bounds : PlausibilityBounds, optional
    """
    b = bounds or PlausibilityBounds()
    if not fit.ok:
        return fit.rejection_reason or "fit rejected"
    if not fit.r_squared >= b.min_r_squared:
        return f"implausible: R^2 {fit.r_squared:.3f} < {b.min_r_squared:g}"
    stiffness = np.asarray(fit.stiffness, float)
    if stiffness.size and not np.all(stiffness >= -STIFFNESS_ROUND_OFF):
        return f"implausible: K(rho) reaches {np.nanmin(stiffness):.3g} N m/rad < 0 during the stance"
    if not stiffness_eq > 0:
        return f"implausible: k_eq {stiffness_eq:.1f} N m/rad is not > 0"
    if not damping_eq >= -b.damping_tolerance:
        return f"implausible: b_eq {damping_eq:.2f} N m s/rad < -{b.damping_tolerance:g} (negative damping)"
    if not body_mass_kg > 0:
        return "implausible: body mass unknown"
    lo, hi, k1_max = table2_band(joint, hop_frequency_hz, body_mass_kg, b)
    k0 = float(fit.coefficients.get("k0", 0.0))
    if not lo <= k0 <= hi:
        return f"implausible: k0 {k0:.1f} N m/rad outside {lo:.1f}..{hi:.1f} (Table 2 x/÷ {b.k0_factor:g}, {body_mass_kg:.1f} kg)"
    k1 = float(fit.coefficients.get("k1", 0.0))
    if not abs(k1) <= k1_max:
        return f"implausible: |k1| {abs(k1):.0f} N m/rad^2 > {k1_max:.0f} (Table 2 x {b.k1_factor:g}, {body_mass_kg:.1f} kg)"
    return None


def controller_damping(damping_eq: float) -> float:
    """The b_eq published for a valid joint: never negative (a small negative OLS value is 0; module docstring)."""
    return max(float(damping_eq), 0.0)
