"""One recording's fits against the seed paper's findings, as lines for a terminal (``hop-impedance demo``).

The seed (000) reports, per hopping frequency: the reduced model K = k0 + k1 (rho - rho0), B = b0
(Eqs. 10-11) with Table 2's k0 and k1; variable stiffness closer to the inverse-dynamics moment than
the best constant stiffness (Table 3); maximal against initial stiffness linear across joints (Fig. 7).
:func:`seed_findings` reads the same four things from one recording's accepted stances:

- k0 and k1 per joint: median over the stances against Table 2 at the nearest seed frequency,
  mass-scaled like the controller's plausibility band (``plausibility.table2_band``: stiffness in
  proportion to body mass);
- how many stances' own diagnostics and F-tests (per stance, before the per-trial structure) keep k1;
- Table 3's direction: stances whose variable-stiffness SSE is below the constant stiffness's;
- Fig. 7: least-squares line of maximal on initial stiffness over every joint's stances, its r^2.

Pure numbers in, lines out (no ROS): the demo builds :class:`JointStance` from its profile messages.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hop_impedance.seed_tables import SUBJECT_MASS_KG, eq10_k0_k1, nearest_frequency_hz

JOINTS = ("ankle", "knee", "hip")


@dataclass(frozen=True)
class JointStance:
    """One accepted stance of one joint (N m/rad, N m/rad^2, N^2 m^2)."""

    k0: float
    k1: float
    stance_keeps_k1: bool  # this stance's own F-tests keep k1
    sse_variable: float
    sse_constant: float
    initial_stiffness: float
    max_stiffness: float


def _pct(value: float, ref: float) -> str:
    return f"{100 * (value / ref - 1):+.0f} %" if ref else "-"


def fig7_line(points: list[tuple[float, float]]) -> tuple[float, float, float]:
    """(slope, intercept, r^2) of maximal on initial stiffness (least squares; NaN below 3 points)."""
    if len(points) < 3:
        return math.nan, math.nan, math.nan
    x, y = np.asarray(points, float).T
    slope, intercept = np.polyfit(x, y, 1)
    r = np.corrcoef(x, y)[0, 1]
    return float(slope), float(intercept), float(r * r)


def seed_findings(stances: dict[str, list[JointStance]], hop_frequency_hz: float, body_mass_kg: float) -> list[str]:
    """Lines comparing ``stances`` (accepted, per joint) with the seed (module docstring)."""
    f = nearest_frequency_hz(hop_frequency_hz)
    scale = body_mass_kg / SUBJECT_MASS_KG if math.isfinite(body_mass_kg) and body_mass_kg > 0 else 1.0
    lines = [f"against the seed (000): hopping at {hop_frequency_hz:.2f} Hz, Table 2 at {f:.2f} Hz scaled to "
             f"{body_mass_kg:.1f} kg (x{scale:.2f})"]
    points = []
    for joint in JOINTS:
        rows = stances.get(joint, [])
        if not rows:
            lines.append(f"  {joint:5s}: no accepted stance")
            continue
        k0_seed, k1_seed = (scale * v for v in eq10_k0_k1(f, joint))
        k0, k1 = (float(np.median([getattr(r, name) for r in rows])) for name in ("k0", "k1"))
        kept = sum(r.stance_keeps_k1 for r in rows)
        below = sum(r.sse_variable < r.sse_constant for r in rows)
        ratio = float(np.median([r.sse_variable / r.sse_constant for r in rows if r.sse_constant > 0] or [math.nan]))
        lines.append(f"  {joint:5s}: k0 {k0:6.0f} vs {k0_seed:4.0f} ({_pct(k0, k0_seed)}), k1 {k1:6.0f} vs "
                     f"{k1_seed:4.0f} ({_pct(k1, k1_seed)}) (medians of {len(rows)} stances); k1 kept by the stance's "
                     f"own F-test in {kept}/{len(rows)}; Table 3: variable SSE below constant in {below}/{len(rows)} "
                     f"(median ratio {ratio:.2f})")
        points += [(r.initial_stiffness, r.max_stiffness) for r in rows
                   if math.isfinite(r.initial_stiffness) and math.isfinite(r.max_stiffness)]
    slope, intercept, r2 = fig7_line(points)
    lines.append(f"  Fig. 7: maximal = {slope:.2f} x initial {intercept:+.0f} N m/rad over {len(points)} joint-stances, "
                 f"r^2 {r2:.2f}")
    return lines
