"""Virtual markers: points a marker set lacks, built from the markers it has by published rules.

Most clinical marker sets have no trochanter marker and often no head marker,
so the contract's ``hip`` and ``head`` (``shared/contract/RECORDINGS.md``) must
be built from other markers. A marker map (``data/marker_maps/*.yaml``)
declares virtual markers by name and uses those names like any lab label::

    virtual_markers:
      RHJC_harrington:                     # a name of your choice
        method: harrington2007             # one of METHODS below
        side: right
        inputs: {rasi: [RASI], lasi: [LASI], rpsi: [RPSI], lpsi: [LPSI]}
    markers:
      hip: [RGT, RHJC_harrington]          # trochanter if marked, else the regression

Each input lists lab labels (first present wins, matched like ``markers``) or
names of virtual markers declared *above* it. A virtual marker is available
only when all its required inputs are present; the import then notes which
label or rule fed each contract marker.

All functions take and return positions in metres, shape (M, 3), in any lab
frame (they are invariant under rigid motion of the lab frame: tested), NaN
where an input is occluded.

Methods
-------
``harrington2007``
    Hip joint centre, Harrington ME, Zavatsky AB, Lawson SEM, Yuan Z,
    Theologis TN (2007) "Prediction of the hip joint centre in adults,
    children, and patients with cerebral palsy based on magnetic resonance
    imaging", J Biomech 40(3):595-602. The single-variable equations the paper
    recommends (no leg length), in mm, in the pelvis frame of the paper
    (origin mid-ASIS, x anterior, y superior, z to the right)::

        x = -0.24 PD - 9.9      y = -0.30 PW - 10.9      z = +/-(0.33 PW + 7.3)

    PW = inter-ASIS distance, PD = distance mid-ASIS to mid-PSIS (the
    sacrum marker stands for mid-PSIS when the set has one sacral marker).
    Inputs ``rasi``, ``lasi`` and ``rpsi`` + ``lpsi`` or ``sacrum``. PW and
    PD are the medians over the frames (the pelvis is rigid; a median is not
    moved by a few bad frames).
``davis1991``
    Hip joint centre, Davis RB, Ounpuu S, Tyburski D, Gage JR (1991) "A gait
    analysis data collection and reduction technique", Hum Mov Sci
    10:575-587, the rule inside Vicon Plug-in Gait / the Conventional Gait
    Model. In mm, pelvis frame origin mid-ASIS, x anterior, y to the left,
    z up; theta = 28.4 deg, beta = 18 deg, r = marker radius, LL = leg length,
    x_dis = ASIS-trochanter distance (default 0.1288 LL - 48.56), C = 0.115 LL - 15.3::

        x = C cos(theta) sin(beta) - (x_dis + r) cos(beta)
        y = S (C sin(theta) - d_ASIS / 2)      (S = +1 right, -1 left, y axis to the left)
        z = -C cos(theta) cos(beta) - (x_dis + r) sin(beta)

    Inputs as ``harrington2007``; options ``leg_length_m`` or
    ``leg_length_parameter`` (a C3D ``PROCESSING`` parameter such as
    ``RLegLength``, mm), optional ``asis_trochanter_parameter``,
    ``inter_asis_parameter`` (Plug-in Gait's ``InterAsisDistance``; default:
    the median marker distance) and ``marker_radius_m`` (default 0.007 m,
    Plug-in Gait's 14 mm markers; else ``MarkerDiameter`` in the file). Without
    a leg length, optional ``knee`` and ``ankle`` inputs give it as the
    marker path ASIS -> knee -> ankle (how Plug-in Gait's is taped).
``mean``
    Mean of the listed markers (e.g. ``RFHD`` + ``RBHD`` = the right side of
    the head at the headband, for the contract's ``head``). Input ``points``.
``hat_top_c7``
    The contract's head point (side of the head, 5 cm above the ear) from the
    spine when the head is not marked: along the trunk line mid-hip -> C7,
    beyond C7 by (1 - f) * head length, where the head (vertex..cervicale)
    and trunk (cervicale..mid-hip) lengths are de Leva's (1996) and f is the
    head marker's depth below the vertex used by the body model
    (:mod:`hop_impedance.biomech.body_model`), so the HAT line and its
    inertia match what the model expects. Inputs ``c7`` and ``hips`` (two hip
    joint centres, or any points whose mean is mid-hip). It follows the
    trunk, not the head: on real Plug-in Gait files it is at the head
    markers' height along the trunk line but 13-18 cm behind the side of the
    head (the head sits forward of the trunk line; test_real_c3d.py), so
    use head markers when the set has them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hop_impedance.biomech.body_model import _HEAD_MARKER_BELOW_VERTEX_FRACTION, DE_LEVA

#: Davis et al. (1991) angles.
DAVIS_THETA_RAD = np.deg2rad(28.4)
DAVIS_BETA_RAD = np.deg2rad(18.0)
#: Plug-in Gait's default marker diameter is 14 mm.
DEFAULT_MARKER_RADIUS_M = 0.007


@dataclass(frozen=True)
class VirtualMarker:
    """A virtual marker declared in a marker map.

    Attributes
    ----------
    name : str
        The label it gets (usable in the map's ``markers``).
    method : str
        A key of :data:`METHODS`.
    inputs : dict of str -> tuple of str
        Role (``rasi``, ``points`` ...) -> candidate labels, first present wins.
    options : dict
        ``side`` and the method's numeric options.
    """

    name: str
    method: str
    inputs: dict[str, tuple[str, ...]]
    options: dict = field(default_factory=dict)


# ---------------------------------------------------------------- geometry


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def pelvis_axes(rasi: np.ndarray, lasi: np.ndarray, mid_psis: np.ndarray) -> tuple[np.ndarray, ...]:
    """Pelvis frame of the ASIS and mid-PSIS markers, frame by frame.

    Returns
    -------
    origin, anterior, left, up : ndarray, shape (M, 3) each
        Origin mid-ASIS; ``left`` along RASI -> LASI; ``anterior``
        perpendicular to it in the plane of the three points, pointing from
        mid-PSIS to mid-ASIS; ``up = anterior x left``.
    """
    origin = 0.5 * (rasi + lasi)
    left = _unit(lasi - rasi)
    back = origin - mid_psis
    anterior = _unit(back - np.sum(back * left, axis=-1, keepdims=True) * left)
    up = np.cross(anterior, left)
    return origin, anterior, left, up


def _sign(side: str) -> float:
    s = str(side).lower()
    if s not in ("right", "left"):
        raise ValueError(f"side must be 'right' or 'left', got {side!r}")
    return 1.0 if s == "right" else -1.0


def _median_distance(a: np.ndarray, b: np.ndarray, what: str) -> float:
    d = np.linalg.norm(a - b, axis=-1)
    if not np.isfinite(d).any():
        raise ValueError(f"{what}: no frame has both markers")
    return float(np.nanmedian(d))


def hjc_harrington2007(rasi: np.ndarray, lasi: np.ndarray, mid_psis: np.ndarray, side: str) -> np.ndarray:
    """Hip joint centre by Harrington et al. (2007), single-variable equations (see module docstring).

    Parameters
    ----------
    rasi, lasi, mid_psis : ndarray, shape (M, 3)
        Right and left ASIS and the PSIS midpoint (or sacrum), metres.
    side : ``"right"`` or ``"left"``

    Returns
    -------
    ndarray, shape (M, 3)
    """
    origin, anterior, left, up = pelvis_axes(rasi, lasi, mid_psis)
    pw_mm = 1e3 * _median_distance(rasi, lasi, "pelvis width")
    pd_mm = 1e3 * _median_distance(origin, mid_psis, "pelvis depth")
    x = -0.24 * pd_mm - 9.9
    y_sup = -0.30 * pw_mm - 10.9
    z_right = _sign(side) * (0.33 * pw_mm + 7.3)
    # Paper frame (x anterior, y superior, z right) -> ours: right = -left.
    return origin + 1e-3 * (x * anterior + y_sup * up - z_right * left)


def davis_leg_length_terms(leg_length_m: float, asis_trochanter_m: float | None = None) -> tuple[float, float]:
    """Davis et al. (1991): ``C`` and the ASIS-trochanter distance ``x_dis`` (m) from the leg length (m)."""
    ll_mm = 1e3 * leg_length_m
    c_mm = 0.115 * ll_mm - 15.3
    x_dis_mm = 0.1288 * ll_mm - 48.56 if asis_trochanter_m is None else 1e3 * asis_trochanter_m
    return 1e-3 * c_mm, 1e-3 * x_dis_mm


def hjc_davis1991(
    rasi: np.ndarray,
    lasi: np.ndarray,
    mid_psis: np.ndarray,
    side: str,
    leg_length_m: float,
    marker_radius_m: float = DEFAULT_MARKER_RADIUS_M,
    asis_trochanter_m: float | None = None,
    inter_asis_m: float | None = None,
) -> np.ndarray:
    """Hip joint centre by Davis et al. (1991), as in Plug-in Gait (see module docstring).

    Parameters
    ----------
    rasi, lasi, mid_psis : ndarray, shape (M, 3)
        Metres; ``mid_psis`` may be the sacrum marker.
    side : ``"right"`` or ``"left"``
    leg_length_m : float
        ASIS to medial malleolus (Plug-in Gait's ``LegLength``).
    marker_radius_m : float
    asis_trochanter_m : float, optional
        Measured ASIS-trochanter distance; default 0.1288 LL - 48.56 mm.
    inter_asis_m : float, optional
        Default: the median RASI-LASI distance of the markers.

    Returns
    -------
    ndarray, shape (M, 3)
    """
    if not 0.3 <= leg_length_m <= 1.5:
        raise ValueError(f"davis1991: leg length {leg_length_m:g} m is implausible (expected 0.3-1.5 m)")
    origin, anterior, left, up = pelvis_axes(rasi, lasi, mid_psis)
    c, x_dis = davis_leg_length_terms(leg_length_m, asis_trochanter_m)
    half_asis = 0.5 * (inter_asis_m if inter_asis_m is not None else _median_distance(rasi, lasi, "inter-ASIS distance"))
    th, be = DAVIS_THETA_RAD, DAVIS_BETA_RAD
    x = c * np.cos(th) * np.sin(be) - (x_dis + marker_radius_m) * np.cos(be)
    y_left = -_sign(side) * (half_asis - c * np.sin(th))
    z = -c * np.cos(th) * np.cos(be) - (x_dis + marker_radius_m) * np.sin(be)
    return origin + x * anterior + y_left * left + z * up


def hat_top_from_c7(c7: np.ndarray, mid_hip: np.ndarray, sex: str = "female") -> np.ndarray:
    """The contract's head point from C7 and mid-hip along the trunk line (de Leva 1996 proportions).

    Returns
    -------
    ndarray, shape (M, 3)
        ``c7 + k (c7 - mid_hip)``, ``k = (1 - f) head_length / trunk_length``.
    """
    table = DE_LEVA[sex]
    k = (1.0 - _HEAD_MARKER_BELOW_VERTEX_FRACTION) * table["head"].length_fraction / table["trunk"].length_fraction
    return c7 + k * (c7 - mid_hip)


# ---------------------------------------------------------------- map side

#: Method -> (required roles, alternative role groups: one group must be complete).
METHODS: dict[str, tuple[tuple[str, ...], tuple[tuple[str, ...], ...]]] = {
    "harrington2007": (("rasi", "lasi"), (("rpsi", "lpsi"), ("sacrum",))),
    "davis1991": (("rasi", "lasi"), (("rpsi", "lpsi"), ("sacrum",))),  # optional: knee, ankle
    "mean": (("points",), ()),
    "hat_top_c7": (("c7", "hips"), ()),
}

#: Roles a method uses when present.
_OPTIONAL_ROLES = {"davis1991": ("knee", "ankle")}

#: Roles that take several markers at once (all those present are used).
_MULTI_ROLES = ("points", "hips")

DESCRIPTIONS = {
    "harrington2007": "hip joint centre, Harrington et al. 2007 (J Biomech 40:595)",
    "davis1991": "hip joint centre, Davis et al. 1991 (Hum Mov Sci 10:575)",
    "mean": "mean of markers",
    "hat_top_c7": "head point on the trunk line beyond C7 (de Leva 1996 proportions)",
}


def virtual_from_dict(name: str, doc: dict, where: str) -> VirtualMarker:
    """Parse one ``virtual_markers`` entry of a map (see module docstring)."""
    if not isinstance(doc, dict) or doc.get("method") not in METHODS:
        raise ValueError(f"{where}: virtual marker {name!r} needs a 'method', one of {', '.join(METHODS)}")
    inputs = doc.get("inputs")
    if not isinstance(inputs, dict):
        raise ValueError(f"{where}: virtual marker {name!r} needs an 'inputs' table (role -> labels)")
    required, groups = METHODS[doc["method"]]
    known = set(required) | {r for g in groups for r in g} | set(_OPTIONAL_ROLES.get(doc["method"], ()))
    unknown = sorted(set(inputs) - known)
    missing = [r for r in required if r not in inputs]
    if unknown or missing or (groups and not any(all(r in inputs for r in g) for g in groups)):
        raise ValueError(
            f"{where}: virtual marker {name!r} ({doc['method']}) takes inputs {', '.join(sorted(known))}"
            + (f"; missing {', '.join(missing)}" if missing else "")
            + (f"; unknown {', '.join(unknown)}" if unknown else "")
        )
    options = {k: v for k, v in doc.items() if k not in ("method", "inputs")}
    if doc["method"] in ("harrington2007", "davis1991"):
        _sign(options.get("side", ""))
    if doc["method"] == "davis1991" and not (
        "leg_length_m" in options or "leg_length_parameter" in options or {"knee", "ankle"} <= set(inputs)
    ):
        raise ValueError(
            f"{where}: virtual marker {name!r} (davis1991) needs leg_length_m, leg_length_parameter or knee + ankle inputs"
        )
    return VirtualMarker(
        str(name),
        str(doc["method"]),
        {r: tuple(str(x) for x in (v if isinstance(v, list) else [v])) for r, v in inputs.items()},
        options,
    )


def _pick(labels: list[str], candidates: tuple[str, ...], multi: bool, find) -> list[int]:
    hits = [h for c in candidates if (h := find(labels, c)) is not None]
    return hits if multi else hits[:1]


def resolve_inputs(vm: VirtualMarker, labels: list[str], find) -> dict[str, list[int]] | None:
    """Label indices of each input role, or None if the virtual marker cannot be built from ``labels``.

    ``find(labels, wanted)`` is the map's label matcher.
    """
    required, groups = METHODS[vm.method]
    picked = {r: _pick(labels, c, r in _MULTI_ROLES, find) for r, c in vm.inputs.items()}
    if any(not picked.get(r) for r in required):
        return None
    if groups:
        group = next((g for g in groups if all(picked.get(r) for r in g)), None)
        if group is None:
            return None
        optional = _OPTIONAL_ROLES.get(vm.method, ())
        picked = {r: v for r, v in picked.items() if r in required or r in group or (r in optional and v)}
    return picked


def missing_inputs(vm: VirtualMarker, labels: list[str], find) -> str:
    """What ``labels`` lack to build ``vm``, e.g. ``"rpsi (RPSI) + lpsi (LPSI) or sacrum (SACR)"``."""
    required, groups = METHODS[vm.method]

    def absent(roles):
        return [f"{r} ({'/'.join(vm.inputs.get(r, ()))})" for r in roles if not _pick(labels, vm.inputs.get(r, ()), True, find)]

    parts = absent(required)
    declared = [g for g in groups if all(r in vm.inputs for r in g)]
    if declared and not any(not absent(g) for g in declared):
        parts.append(" or ".join(" + ".join(absent(g)) for g in declared))
    return ", ".join(parts)


def _file_length_m(parameters: dict[str, float], name: str | None) -> float | None:
    """A positive length parameter of the file in metres, or None if absent or zero."""
    hit = next((v for k, v in parameters.items() if name is not None and k.lower() == str(name).lower()), None)
    if hit is None or not float(hit) > 0:
        return None
    # Vicon writes subject lengths in mm; a length above 3 cannot be metres.
    return float(hit) / 1000.0 if float(hit) > 3.0 else float(hit)


def _davis_options(vm: VirtualMarker, get: dict, params: dict[str, float]) -> tuple[dict, list[str]]:
    """Leg length, marker radius, ASIS-trochanter and inter-ASIS distances for davis1991, with notes."""
    o, notes = vm.options, []
    ll = float(o["leg_length_m"]) if "leg_length_m" in o else _file_length_m(params, o.get("leg_length_parameter"))
    if ll is not None:
        notes.append(f"leg length {ll:.3f} m" + (f" from {o['leg_length_parameter']}" if "leg_length_m" not in o else ""))
    elif "knee" in get and "ankle" in get:
        # Plug-in Gait's leg length is taped ASIS -> knee -> medial malleolus; the markers give the same path.
        asis = get["rasi" if _sign(o["side"]) > 0 else "lasi"][:, 0]
        ll = _median_distance(asis, get["knee"][:, 0], "ASIS-knee") + _median_distance(
            get["knee"][:, 0], get["ankle"][:, 0], "knee-ankle"
        )
        notes.append(f"leg length {ll:.3f} m from the ASIS->knee->ankle markers")
    else:
        raise ValueError(
            f"virtual marker {vm.name!r} (davis1991): no leg length (the file has no "
            f"{o.get('leg_length_parameter', 'leg length parameter')}, and no knee/ankle markers); give leg_length_m"
        )
    radius = o.get("marker_radius_m")
    if radius is None:
        diameter = _file_length_m(params, "MarkerDiameter")
        radius = DEFAULT_MARKER_RADIUS_M if diameter is None else 0.5 * diameter
    notes.append(f"marker radius {1e3 * float(radius):.1f} mm")
    xdis = _file_length_m(params, o.get("asis_trochanter_parameter"))
    if xdis is not None:
        notes.append(f"ASIS-trochanter {xdis:.4f} m from {o['asis_trochanter_parameter']}")
    inter = _file_length_m(params, o.get("inter_asis_parameter"))
    if inter is not None:
        notes.append(f"inter-ASIS {inter:.3f} m from {o['inter_asis_parameter']}")
    return dict(leg_length_m=ll, marker_radius_m=float(radius), asis_trochanter_m=xdis, inter_asis_m=inter), notes


def compute(
    vm: VirtualMarker,
    labels: list[str],
    positions: np.ndarray,
    picked: dict[str, list[int]],
    parameters: dict[str, float] | None = None,
    sex: str = "female",
) -> tuple[np.ndarray, str]:
    """Positions (M, 3) of one virtual marker and a one-line note saying how it was built."""
    params = parameters or {}
    get = {r: positions[:, idx, :] for r, idx in picked.items()}
    used = ", ".join(labels[i] for idx in picked.values() for i in idx)
    o = vm.options
    if vm.method in ("harrington2007", "davis1991"):
        rear = get["sacrum"][:, 0] if "sacrum" in get else 0.5 * (get["rpsi"][:, 0] + get["lpsi"][:, 0])
        rasi, lasi = get["rasi"][:, 0], get["lasi"][:, 0]
        if vm.method == "harrington2007":
            pos = hjc_harrington2007(rasi, lasi, rear, o["side"])
            return pos, f"{DESCRIPTIONS[vm.method]}, {o['side']}, from {used}"
        kwargs, extra = _davis_options(vm, get, params)
        # knee/ankle only feed a leg length the file lacks (the note says so)
        used = ", ".join(labels[i] for r, idx in picked.items() if r not in ("knee", "ankle") for i in idx)
        pos = hjc_davis1991(rasi, lasi, rear, o["side"], **kwargs)
        return pos, f"{DESCRIPTIONS[vm.method]}, {o['side']}, from {used} ({'; '.join(extra)})"
    if vm.method == "mean":
        return np.mean(get["points"], axis=1), f"{DESCRIPTIONS[vm.method]} {used}"
    # hat_top_c7
    pos = hat_top_from_c7(get["c7"][:, 0], np.mean(get["hips"], axis=1), sex)
    return pos, f"{DESCRIPTIONS[vm.method]}, from {used} ({sex} table)"
