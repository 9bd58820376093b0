"""A second, independent hopping generator: the strict stance family of issue 16.

Shares no code with ``hop_impedance.simulation`` or ``hop_impedance.discovery`` (a test checks the
imports): its own segment table (Winter 2009, both legs lumped; masses, lengths, centre-of-mass
positions and radii of gyration each perturbed by up to +-5 %), its own coordinates (toe height, foot
angle and three *relative* joint angles, toe pinned horizontally), equations of motion derived
symbolically with sympy (projection of the segments' Newton-Euler equations on the coordinates),
another integrator (``DOP853``), a lossless near-rigid ground (``Fz = k |y|^1.5``, no damper) and
time-symmetric conservative stances started from a random mid-stance posture at rest. See
:func:`strict_recording`.
"""

from hop_impedance.validation.strict_generator.generator import StrictConfig, strict_recording

__all__ = ["StrictConfig", "strict_recording"]
