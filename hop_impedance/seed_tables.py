"""The seed paper's published numbers, typed once.

Source: ../shared/seeds/000_*.txt, "Constant and Variable Stiffness and
Damping of the Leg Joints in Human Hopping", J. Biomech. Eng. (2003),
DOI 10.1115/1.1590358: Methods (subjects), Table 1 (kinematics and kinetics
of the stance) and Table 2 (stiffness; k0, k1 of its Eq. 10,
``K = k0 + k1 (rho - rho0)``, with a constant damping "below 0.72 N m s/rad").
All values are the tables' means over the 8 subjects; SDs are given where
code uses them. Angles in rad, stiffness in N m/rad (the paper prints k1 in
"Nm rad^-1" too; by Eq. 10 its unit is N m/rad^2), times in s.

Every table is ``{frequency_hz: {joint: value}}`` with the seed's hopping
frequencies 1.53, 1.87 and 2.20 Hz and joints "ankle", "knee", "hip".
"""

from __future__ import annotations

from dataclasses import dataclass

#: The seed's hopping frequencies (Hz), Tables 1 and 2.
FREQUENCIES_HZ: tuple[float, ...] = (1.53, 1.87, 2.20)
#: Joints of Tables 1 and 2, in the package's joint order.
JOINTS: tuple[str, ...] = ("ankle", "knee", "hip")

#: Methods: "body mass 54.8 (SD, 4.8) kg, and body height 1.63 (SD, 0.02) m" (8 women).
SUBJECT_MASS_KG = 54.8
SUBJECT_HEIGHT_M = 1.63

#: Table 1, stance time (s): 458, 333, 282 ms.
STANCE_TIME_S: dict[float, float] = {1.53: 0.458, 1.87: 0.333, 2.20: 0.282}

#: Table 1, range of flexion (rad) per joint.
RANGE_OF_FLEXION_RAD: dict[float, dict[str, float]] = {
    1.53: {"ankle": 0.85, "knee": 0.70, "hip": 0.37},
    1.87: {"ankle": 0.69, "knee": 0.42, "hip": 0.18},
    2.20: {"ankle": 0.59, "knee": 0.27, "hip": 0.11},
}

#: Results: "The value of the damping coefficient was below 0.72 Nms/rad" (N m s/rad).
DAMPING_UPPER_BOUND_NM_S_RAD = 0.72


@dataclass(frozen=True)
class Eq10Stiffness:
    """Table 2's Eq. 10 coefficients of one joint at one frequency: mean (SD) over the subjects.

    Attributes
    ----------
    k0, k0_sd : float
        Touchdown stiffness (N m/rad).
    k1, k1_sd : float
        Stiffness slope with flexion (N m/rad^2).
    """

    k0: float
    k0_sd: float
    k1: float
    k1_sd: float


#: Table 2, k0 and k1 of Eq. 10, mean (SD).
TABLE2_EQ10: dict[float, dict[str, Eq10Stiffness]] = {
    1.53: {
        "ankle": Eq10Stiffness(178.5, 32.3, 193.3, 39.7),
        "knee": Eq10Stiffness(110.0, 29.6, 169.3, 33.6),
        "hip": Eq10Stiffness(95.3, 37.0, 161.8, 24.1),
    },
    1.87: {
        "ankle": Eq10Stiffness(223.3, 57.4, 560.8, 96.0),
        "knee": Eq10Stiffness(158.8, 67.1, 541.3, 77.5),
        "hip": Eq10Stiffness(139.4, 31.5, 526.9, 96.6),
    },
    2.20: {
        "ankle": Eq10Stiffness(301.4, 63.4, 948.2, 149.4),
        "knee": Eq10Stiffness(230.9, 66.6, 884.8, 175.4),
        "hip": Eq10Stiffness(175.4, 28.0, 894.8, 172.3),
    },
}

#: Table 2, overall joint stiffness (moment change over angle change, N m/rad), means.
TABLE2_OVERALL_NM_RAD: dict[float, dict[str, float]] = {
    1.53: {"ankle": 278.8, "knee": 142.0, "hip": 104.1},
    1.87: {"ankle": 434.3, "knee": 292.4, "hip": 224.4},
    2.20: {"ankle": 584.8, "knee": 470.8, "hip": 380.6},
}

#: Table 2, model-average stiffness (mean of K over the stance, N m/rad), means.
TABLE2_AVERAGE_NM_RAD: dict[float, dict[str, float]] = {
    1.53: {"ankle": 268.5, "knee": 153.2, "hip": 127.8},
    1.87: {"ankle": 426.2, "knee": 270.6, "hip": 218.6},
    2.20: {"ankle": 586.6, "knee": 471.6, "hip": 277.3},
}


def nearest_frequency_hz(frequency_hz: float) -> float:
    """The seed frequency (Hz) closest to ``frequency_hz``."""
    return min(FREQUENCIES_HZ, key=lambda f: abs(f - frequency_hz))


def eq10_k0_k1(frequency_hz: float, joint: str) -> tuple[float, float]:
    """Table 2 means ``(k0, k1)`` (N m/rad, N m/rad^2) of ``joint`` at a seed frequency."""
    row = TABLE2_EQ10[frequency_hz][joint]
    return row.k0, row.k1
