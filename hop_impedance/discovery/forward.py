"""What a held-out stance is compared on, and the ground it is simulated on.

The held-out forward runs themselves are in
:mod:`hop_impedance.discovery.forward_selection`; each stance is compared sample by
sample (force-plate rate) on :data:`GAP_SIGNALS`:

- ``grf``: raw vertical plate force (N); the model's prediction is the
  simulated Fz plus the model's plate offset;
- ``angle_<joint>``: joint angles (rad);
- ``moment_<joint>``: ID moments (N m) against the simulated law moments.
"""

from __future__ import annotations

from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.discovery.identify import surface_law
from hop_impedance.discovery.measurement import MeasuredStance
from hop_impedance.discovery.model import ModelSpec
from hop_impedance.simulation.ground import GroundLaw
from hop_impedance.simulation.stance_set import RIGID_NO_BOUNCE

GAP_SIGNALS: tuple[str, ...] = ("grf",) + tuple(f"angle_{j}" for j in JOINT_NAMES) + tuple(f"moment_{j}" for j in JOINT_NAMES)
#: The ten terms of a held-out stance's gap ``G_i`` in order: the sampled signals, then the stance duration, the net
#: joint work and the flight's plate force (:func:`hop_impedance.discovery.forward_selection.gap_scales`).
GAP_TERMS: tuple[str, ...] = GAP_SIGNALS + ("duration", "net_work", "flight_force")


def ground_of(spec: ModelSpec, s: MeasuredStance) -> GroundLaw:
    """Surface law under stance ``s``: rigid (no bounce) or the identified ``k |y|^n - d y'``."""
    law = surface_law(spec, s)
    if law is None or law[0] <= 0:
        return RIGID_NO_BOUNCE
    c, p, d = law
    return GroundLaw("identified", float(c ** (-1.0 / p)), float(1.0 / p), float(d))
