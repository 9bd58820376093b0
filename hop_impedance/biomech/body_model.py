"""Four-segment sagittal body model scaled with de Leva (1996).

The seed paper's model: feet, shanks, thighs and HAT (head, arms, trunk) as
rigid links in the sagittal plane, both legs lumped into one (masses and
moments of inertia of the paired segments added). The foot touches the ground
at the toe marker (a virtual hinge at the fifth metatarsal head).

Every segment is described in its own frame: origin at its distal joint
(toe, ankle, knee, hip), first axis along the line from the distal to the
proximal joint (toe->ankle, ankle->knee, knee->hip, hip->head marker), second
axis that line rotated by +90 degrees in the x-z picture (x forward, z up,
counter-clockwise positive, i.e. the view from the subject's right side).

References
----------
de Leva P. (1996) Adjustments to Zatsiorsky-Seluyanov's segment inertia
parameters. J Biomech 29(9):1223-1230, Table 4 (mass fractions, centre-of-mass
locations and sagittal radii of gyration, in % of segment length, for women and
men) and the segment lengths of its reference subjects.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import NamedTuple

import numpy as np

from hop_impedance.recording import Subject


class DeLevaSegment(NamedTuple):
    """One row of de Leva's Table 4.

    mass_fraction : fraction of body mass (one side).
    com_fraction : centre of mass from the proximal end, fraction of segment length.
    gyration_fraction : sagittal radius of gyration about the COM, fraction of length.
    length_fraction : segment length of de Leva's reference subject / its stature.
    """

    mass_fraction: float
    com_fraction: float
    gyration_fraction: float
    length_fraction: float


# Reference statures of de Leva's tables (m).
_STATURE_M = {"female": 1.735, "male": 1.741}

# de Leva (1996) Table 4. Endpoints: head = vertex..cervicale, trunk =
# cervicale..mid-hip, upper arm = shoulder..elbow, forearm = elbow..wrist,
# hand = wrist..3rd finger tip, thigh = hip..knee joint centre,
# shank = knee joint centre..lateral malleolus, foot = heel..toe tip.
DE_LEVA: dict[str, dict[str, DeLevaSegment]] = {
    "female": {
        "head": DeLevaSegment(0.0668, 0.5894, 0.330, 0.2437 / 1.735),
        "trunk": DeLevaSegment(0.4257, 0.4151, 0.357, 0.6148 / 1.735),
        "upper_arm": DeLevaSegment(0.0255, 0.5754, 0.278, 0.2751 / 1.735),
        "forearm": DeLevaSegment(0.0138, 0.4559, 0.261, 0.2643 / 1.735),
        "hand": DeLevaSegment(0.0056, 0.7474, 0.531, 0.1701 / 1.735),
        "thigh": DeLevaSegment(0.1478, 0.3612, 0.369, 0.3685 / 1.735),
        "shank": DeLevaSegment(0.0481, 0.4416, 0.271, 0.4323 / 1.735),
        "foot": DeLevaSegment(0.0129, 0.4014, 0.299, 0.2283 / 1.735),
    },
    "male": {
        "head": DeLevaSegment(0.0694, 0.5976, 0.362, 0.2429 / 1.741),
        "trunk": DeLevaSegment(0.4346, 0.4486, 0.372, 0.6033 / 1.741),
        "upper_arm": DeLevaSegment(0.0271, 0.5772, 0.285, 0.2817 / 1.741),
        "forearm": DeLevaSegment(0.0162, 0.4574, 0.276, 0.2689 / 1.741),
        "hand": DeLevaSegment(0.0061, 0.7900, 0.628, 0.1879 / 1.741),
        "thigh": DeLevaSegment(0.1416, 0.4095, 0.329, 0.4222 / 1.741),
        "shank": DeLevaSegment(0.0433, 0.4459, 0.255, 0.4340 / 1.741),
        "foot": DeLevaSegment(0.0137, 0.4415, 0.257, 0.2581 / 1.741),
    },
}

#: Default sex when none is given: the seed paper's eight subjects were women.
DEFAULT_SEX = "female"

# Foot geometry used with the markers (Winter 2009, Table 4.1 landmarks): the
# fifth metatarsal head lies at about 72 % of the heel..toe-tip length from the
# heel; the foot's centre of mass sits at about 40 % of the malleolus height
# above the sole.
_TOE_MARKER_FRACTION_OF_FOOT_LENGTH = 0.72
_FOOT_COM_HEIGHT_FRACTION = 0.40

# Arms of the HAT with the hands on the waist (the seed's protocol). Heights of
# the arm segments' centres of mass above the hip, as fractions of the trunk
# length: upper arm hangs from the shoulder, forearm slopes to the waist, hand
# rests on the iliac crest.
_ARM_COM_HEIGHT_FRACTION_OF_TRUNK = {"upper_arm": 0.75, "forearm": 0.45, "hand": 0.25}
# The head marker (5 cm above the top of the ear) lies about a third of the
# head length (vertex..cervicale) below the vertex.
_HEAD_MARKER_BELOW_VERTEX_FRACTION = 0.33

SEGMENT_NAMES: tuple[str, ...] = ("foot", "shank", "thigh", "hat")


@dataclass(frozen=True)
class Segment:
    """Inertial parameters of one (lumped) segment in its own frame.

    Attributes
    ----------
    name : str
        ``foot``, ``shank``, ``thigh`` or ``hat``.
    mass_kg : float
        Mass (kg); for foot, shank and thigh both legs together.
    length_m : float
        Distal joint to proximal joint (m): toe->ankle, ankle->knee,
        knee->hip, hip->head marker.
    com_along_m : float
        Centre of mass along the distal->proximal axis, from the distal joint (m).
    com_perp_m : float
        Centre of mass along the perpendicular axis (the axis rotated +90 deg
        counter-clockwise in the x-z picture) (m).
    inertia_kgm2 : float
        Moment of inertia about the centre of mass, sagittal axis (kg m^2).
    """

    name: str
    mass_kg: float
    length_m: float
    com_along_m: float
    com_perp_m: float
    inertia_kgm2: float


@dataclass(frozen=True)
class FootGeometry:
    """Shape of the foot triangle toe-heel-ankle in the foot frame (toe at origin).

    Attributes
    ----------
    toe_ankle_m : float
        Distance toe -> ankle (the foot link) (m).
    heel_along_m, heel_perp_m : float
        Heel marker in the foot frame (m).
    """

    toe_ankle_m: float
    heel_along_m: float
    heel_perp_m: float

    @property
    def alpha_rad(self) -> float:
        """Constant foot angle alpha of Eq. 2 (rad).

        Chosen as the angle at the toe between the toe->heel line (the sole)
        and the toe->ankle line, so that ``rho1 = q1 - q2 + alpha`` is the
        angle between the sole (pointing backwards) and the shank: 90 deg when
        the shank stands perpendicular to the sole, larger in dorsiflexion.
        """
        return float(np.arctan2(self.heel_perp_m, self.heel_along_m))

    @property
    def heel_toe_m(self) -> float:
        """Heel marker to toe marker distance (m)."""
        return float(np.hypot(self.heel_along_m, self.heel_perp_m))


@dataclass(frozen=True)
class BodyModel:
    """The four lumped segments plus the foot shape.

    Attributes
    ----------
    foot, shank, thigh, hat : Segment
    foot_geometry : FootGeometry
    body_mass_kg : float
    sex : str
    """

    foot: Segment
    shank: Segment
    thigh: Segment
    hat: Segment
    foot_geometry: FootGeometry
    body_mass_kg: float
    sex: str

    @property
    def segments(self) -> tuple[Segment, Segment, Segment, Segment]:
        """Segments from the ground up: foot, shank, thigh, HAT."""
        return (self.foot, self.shank, self.thigh, self.hat)

    @property
    def total_mass_kg(self) -> float:
        """Sum of the segment masses (kg); equals body mass unless overridden."""
        return float(sum(s.mass_kg for s in self.segments))


def _table(sex: str) -> dict[str, DeLevaSegment]:
    try:
        return DE_LEVA[sex]
    except KeyError:
        raise ValueError(f"sex must be 'female' or 'male', got {sex!r}") from None


def _limb_segment(name: str, sex: str, mass_kg: float, length_m: float) -> Segment:
    """Lumped (two-leg) shank or thigh; COM from de Leva's proximal fraction."""
    row = _table(sex)[name]
    mass = 2.0 * row.mass_fraction * mass_kg
    com_from_distal = (1.0 - row.com_fraction) * length_m
    inertia = mass * (row.gyration_fraction * length_m) ** 2
    return Segment(name, mass, length_m, com_from_distal, 0.0, inertia)


def _foot_segment(sex: str, mass_kg: float, geometry: FootGeometry) -> Segment:
    """Lumped feet. COM from de Leva's heel fraction on the heel->toe-tip line,
    raised to 40 % of the malleolus height; inertia from the sagittal radius of
    gyration of the full foot length."""
    row = _table(sex)["foot"]
    mass = 2.0 * row.mass_fraction * mass_kg
    heel = np.array([geometry.heel_along_m, geometry.heel_perp_m])
    ankle = np.array([geometry.toe_ankle_m, 0.0])
    foot_length = geometry.heel_toe_m / _TOE_MARKER_FRACTION_OF_FOOT_LENGTH
    sole_dir = -heel / np.linalg.norm(heel)  # heel -> toe
    up = np.array([-sole_dir[1], sole_dir[0]])
    if np.dot(up, ankle - heel) < 0:
        up = -up
    ankle_height = float(np.dot(ankle - heel, up))
    com = heel + row.com_fraction * foot_length * sole_dir + _FOOT_COM_HEIGHT_FRACTION * ankle_height * up
    inertia = mass * (row.gyration_fraction * foot_length) ** 2
    return Segment("foot", mass, geometry.toe_ankle_m, float(com[0]), float(com[1]), inertia)


def _hat_segment(sex: str, mass_kg: float, length_m: float, stature_m: float) -> Segment:
    """Head, arms (hands on the waist) and trunk as one rigid body.

    The composite's centre of mass and inertia are computed from de Leva's
    rows placed on a vertical line above the hip for the reference proportions
    of ``stature_m``, then expressed as fractions of the hip->head-marker
    distance and applied to ``length_m``.
    """
    table = _table(sex)
    trunk_len = table["trunk"].length_fraction * stature_m
    head_len = table["head"].length_fraction * stature_m
    heights = {
        "trunk": (1.0 - table["trunk"].com_fraction) * trunk_len,
        "head": trunk_len + (1.0 - table["head"].com_fraction) * head_len,
    }
    lengths = {"trunk": trunk_len, "head": head_len}
    for arm, frac in _ARM_COM_HEIGHT_FRACTION_OF_TRUNK.items():
        heights[arm] = frac * trunk_len
        lengths[arm] = table[arm].length_fraction * stature_m
    masses = {
        k: (1.0 if k in ("trunk", "head") else 2.0) * table[k].mass_fraction * mass_kg for k in heights
    }
    total = sum(masses.values())
    com_height = sum(masses[k] * heights[k] for k in heights) / total
    inertia = sum(
        masses[k] * ((table[k].gyration_fraction * lengths[k]) ** 2 + (heights[k] - com_height) ** 2)
        for k in heights
    )
    ref_length = trunk_len + (1.0 - _HEAD_MARKER_BELOW_VERTEX_FRACTION) * head_len
    scale = length_m / ref_length
    return Segment("hat", total, length_m, com_height * scale, 0.0, inertia * scale**2)


def default_foot_geometry(body_height_m: float, sex: str = DEFAULT_SEX) -> FootGeometry:
    """Foot triangle scaled from stature when no markers are available (m).

    Heel marker below the malleolus on the sole; toe marker at 72 % of the
    de Leva foot length in front of the heel; malleolus height 3.9 % of
    stature (Winter 2009, Fig. 4.1: 0.039 H).
    """
    foot_length = _table(sex)["foot"].length_fraction * body_height_m
    heel_toe = _TOE_MARKER_FRACTION_OF_FOOT_LENGTH * foot_length
    ankle_height = 0.039 * body_height_m
    # In a frame with the toe at the origin and the sole along -x (towards the heel):
    heel = np.array([-heel_toe, 0.0])
    ankle = np.array([-heel_toe, ankle_height])
    return foot_geometry_from_points(np.zeros(2), heel, ankle)


def foot_geometry_from_points(toe: np.ndarray, heel: np.ndarray, ankle: np.ndarray) -> FootGeometry:
    """Foot triangle from three sagittal points ``[x, z]`` (m), expressed in the foot frame."""
    axis = np.asarray(ankle, float) - np.asarray(toe, float)
    length = float(np.hypot(*axis))
    if not length > 0:
        raise ValueError("toe and ankle markers coincide: cannot define the foot segment")
    e1 = axis / length
    e2 = np.array([-e1[1], e1[0]])
    rel = np.asarray(heel, float) - np.asarray(toe, float)
    return FootGeometry(length, float(rel @ e1), float(rel @ e2))


def body_model(
    body_mass_kg: float,
    lengths_m: dict[str, float],
    foot_geometry: FootGeometry,
    sex: str = DEFAULT_SEX,
    stature_m: float = 1.65,
) -> BodyModel:
    """Scale de Leva (1996) to a subject.

    Parameters
    ----------
    body_mass_kg : float
        Body mass (kg).
    lengths_m : dict
        ``shank``, ``thigh``, ``hat`` lengths (m) between the contract's markers.
    foot_geometry : FootGeometry
        Foot triangle (sets the foot link length and the foot's COM).
    sex : {"female", "male"}
        Table to use; default female (the seed's subjects).
    stature_m : float
        Body height (m); only used to place the HAT's component segments.
    """
    if not body_mass_kg > 0:
        raise ValueError(f"body_mass_kg must be positive, got {body_mass_kg}")
    for key in ("shank", "thigh", "hat"):
        if not lengths_m.get(key, 0) > 0:
            raise ValueError(f"segment length {key!r} must be positive, got {lengths_m.get(key)}")
    return BodyModel(
        foot=_foot_segment(sex, body_mass_kg, foot_geometry),
        shank=_limb_segment("shank", sex, body_mass_kg, lengths_m["shank"]),
        thigh=_limb_segment("thigh", sex, body_mass_kg, lengths_m["thigh"]),
        hat=_hat_segment(sex, body_mass_kg, lengths_m["hat"], stature_m),
        foot_geometry=foot_geometry,
        body_mass_kg=body_mass_kg,
        sex=sex,
    )


def body_model_from_stature(subject: Subject) -> BodyModel:
    """Model with every length scaled from stature (no markers): used by the simulator.

    The hip->head-marker length is de Leva's trunk plus two thirds of the head.
    """
    table = _table(subject.sex)
    h = subject.body_height_m
    lengths = {
        "shank": table["shank"].length_fraction * h,
        "thigh": table["thigh"].length_fraction * h,
        "hat": (table["trunk"].length_fraction + (1 - _HEAD_MARKER_BELOW_VERTEX_FRACTION) * table["head"].length_fraction) * h,
    }
    return body_model(subject.body_mass_kg, lengths, default_foot_geometry(h, subject.sex), subject.sex, h)


def with_overrides(model: BodyModel, overrides: dict[str, dict[str, float]]) -> BodyModel:
    """Replace segment parameters, e.g. ``{"hat": {"mass_kg": 35.0}}``.

    Keys are segment names; values map :class:`Segment` field names to numbers.
    Unknown segments or fields raise ``ValueError`` naming them.
    """
    updated = {}
    for name, fields in overrides.items():
        if name not in SEGMENT_NAMES:
            raise ValueError(f"unknown segment {name!r} in overrides; expected one of {SEGMENT_NAMES}")
        seg = getattr(model, name)
        bad = set(fields) - {"mass_kg", "length_m", "com_along_m", "com_perp_m", "inertia_kgm2"}
        if bad:
            raise ValueError(f"unknown field(s) {sorted(bad)} for segment {name!r}")
        updated[name] = replace(seg, **{k: float(v) for k, v in fields.items()})
    return replace(model, **updated)


def load_overrides(path: str | Path) -> dict[str, dict[str, float]]:
    """Read a YAML file of per-segment overrides (see :func:`with_overrides`)."""
    import yaml

    with open(path, encoding="utf-8") as fh:
        data = yaml.safe_load(fh) or {}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a mapping of segment name -> fields")
    return data
