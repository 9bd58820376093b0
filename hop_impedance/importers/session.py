"""Lab session (lab frame, SI units) -> contract :class:`~hop_impedance.recording.Recording`.

Every reader (C3D, TRC/MOT, force-only text) first produces a
:class:`LabSession`: the file's content converted to SI units but still in the
lab's own axes and with the lab's marker labels. :func:`session_to_recording`
then does the steps common to all formats:

1. check that each stream has one constant sampling rate;
2. build the mapping's virtual markers (hip joint centre by regression ...,
   :mod:`virtual_markers`), pick the contract's six markers with a
   :class:`MarkerMapping` and note which label or rule fed each;
3. find the vertical (file hint, option, or toe->head) and the heading
   (option, or rear->front marker pairs), build the rotation to the contract
   frame (:mod:`frames`);
4. sum the plates' wrenches about one common origin on the ground, which
   becomes the contract frame's origin (:mod:`plates`), and turn it into the
   reaction on the subject;
5. resolve the subject's mass and height (option > file > estimate with a
   warning > clear error).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hop_impedance.importers.frames import detect_forward, detect_up_axis, parse_axis, rotation_to_contract, to_contract
from hop_impedance.importers.marker_mapping import (
    MarkerMapping,
    contract_markers,
    forward_pair_positions,
    source_notes,
    with_virtual_markers,
)
from hop_impedance.importers.plates import orient_reaction, total_wrench
from hop_impedance.recording import GRAVITY_M_S2, MARKER_NAMES, ForcePlateSeries, MarkerSeries, Recording, Subject

#: Contract rates (RECORDINGS.md); outside them the import warns, it does not refuse.
CONTRACT_FORCE_RATE_HZ = (500.0, 2000.0)
CONTRACT_MARKER_RATE_HZ = (50.0, 250.0)


@dataclass
class PlateData:
    """One force plate in lab axes, SI units.

    Attributes
    ----------
    force_n : ndarray, shape (N, 3)
        Force (N) as the file gives it (action on the plate or reaction on
        the subject; :func:`~hop_impedance.importers.plates.orient_reaction` decides).
    moment_nm : ndarray, shape (N, 3)
        Moment (N m) about ``point_m``.
    point_m : ndarray, shape (N, 3) or (3,)
        Reference point of the moment (m): the plate's top centre or the COP.
    name : str
    """

    force_n: np.ndarray
    moment_nm: np.ndarray
    point_m: np.ndarray
    name: str = ""


@dataclass
class LabSession:
    """A lab file's content in lab axes and SI units, before mapping to the contract.

    Attributes
    ----------
    marker_time_s : ndarray, shape (M,) or None
        Marker frame times (s); None for force-only sessions.
    marker_labels : tuple of str
    marker_positions_m : ndarray, shape (M, L, 3) or None
        All markers (m); NaN where occluded.
    force_time_s : ndarray, shape (N,)
        Force sample times (s).
    plates : list of PlateData
    origin_m : ndarray, shape (3,) or None
        Common origin for the plates' moments (m, lab); None = the lab
        origin dropped to the ground level of the loaded centres of pressure.
    up_hint : str or None
        Vertical axis stated by the file (``"+Z"``); None if it says nothing.
    body_mass_kg, body_height_m : float or None
        From the file's parameters, if any.
    subject_id : str
    source : str
    warnings : list of str
    parameters : dict of str -> float
        The file's numeric subject parameters by name (C3D ``PROCESSING``,
        e.g. ``RLegLength`` in mm), for virtual markers that need them.
    """

    marker_time_s: np.ndarray | None
    marker_labels: tuple[str, ...]
    marker_positions_m: np.ndarray | None
    force_time_s: np.ndarray
    plates: list[PlateData]
    origin_m: np.ndarray | None = None
    up_hint: str | None = None
    body_mass_kg: float | None = None
    body_height_m: float | None = None
    subject_id: str = ""
    source: str = ""
    warnings: list[str] = field(default_factory=list)
    parameters: dict[str, float] = field(default_factory=dict)


def sampling_rate_hz(time_s: np.ndarray, what: str, rel_tol: float = 0.01) -> float:
    """Constant sampling rate (Hz) of a time column, or a clear error.

    Raises
    ------
    ValueError
        If there are fewer than 2 samples, times are not increasing, or any
        interval differs from the median by more than ``rel_tol`` (relative).
    """
    t = np.asarray(time_s, float)
    if t.size < 2:
        raise ValueError(f"{what}: needs at least 2 samples to know its rate, got {t.size}")
    dt = np.diff(t)
    med = float(np.median(dt))
    if not np.all(np.isfinite(dt)) or med <= 0 or np.any(dt <= 0):
        raise ValueError(f"{what}: times must increase strictly")
    worst = float(np.max(np.abs(dt - med)) / med)
    if worst > rel_tol:
        raise ValueError(
            f"{what}: inconsistent sampling rate: intervals range {dt.min():.6g}-{dt.max():.6g} s "
            f"(median {med:.6g} s, {100 * worst:.1f} % off > {100 * rel_tol:g} %)"
        )
    return 1.0 / med


def estimate_mass_from_quiet_stance(time_s: np.ndarray, fz_n: np.ndarray, window_s: float = 1.0) -> tuple[float, float]:
    """Body mass (kg) from the steadiest loaded window of the vertical force.

    Slides a ``window_s`` window over the loaded samples and takes the one
    with the smallest coefficient of variation of Fz; mass = mean Fz / g.

    Parameters
    ----------
    time_s : ndarray, shape (N,)
    fz_n : ndarray, shape (N,)
        Vertical ground reaction force (N), positive up.
    window_s : float
        Window length (s).

    Returns
    -------
    mass_kg : float
    start_s : float
        Start of the window used.

    Raises
    ------
    ValueError
        If no window has a mean above 100 N with a coefficient of variation
        below 5 % (no quiet stance in the file).
    """
    rate = sampling_rate_hz(time_s, "force")
    n = max(int(round(window_s * rate)), 2)
    fz = np.asarray(fz_n, float)
    if fz.size < n:
        raise ValueError(f"cannot estimate the body mass: the force record is shorter than {window_s:g} s")
    windows = np.lib.stride_tricks.sliding_window_view(fz, n)
    mean = windows.mean(axis=1)
    cv = np.where(mean > 100.0, windows.std(axis=1) / np.maximum(mean, 1e-9), np.inf)
    k = int(np.argmin(cv))
    if not np.isfinite(cv[k]) or cv[k] > 0.05:
        raise ValueError(
            f"cannot estimate the body mass: no {window_s:g} s of quiet standing (Fz > 100 N varying < 5 %); "
            "give the mass (--mass-kg)"
        )
    return float(mean[k] / GRAVITY_M_S2), float(time_s[k])


def _stamps_ns(time_s: np.ndarray) -> np.ndarray:
    return np.round(np.asarray(time_s, float) * 1e9).astype(np.int64)


def _rate_warning(rate: float, band: tuple[float, float], what: str) -> str | None:
    if band[0] <= rate <= band[1]:
        return None
    return f"{what} rate {rate:g} Hz is outside the contract's {band[0]:g}-{band[1]:g} Hz"


def _ground_origin(plates: list[PlateData], rotation: np.ndarray) -> np.ndarray:
    """Lab origin dropped to the median vertical level of the loaded centres of pressure (m)."""
    up = rotation[2]
    levels = []
    for p in plates:
        pts = np.broadcast_to(np.asarray(p.point_m, float), p.force_n.shape)
        loaded = np.abs(p.force_n @ up) > 20.0
        levels.append(pts[loaded] @ up)
    level = np.concatenate(levels) if levels else np.empty(0)
    level = level[np.isfinite(level)]
    return up * (float(np.median(level)) if level.size else 0.0)


def _resolve_axes(
    session: LabSession,
    mapping: MarkerMapping | None,
    picked: _PickedMarkers | None,
    up: str | None,
    forward: str | None,
) -> tuple[np.ndarray, list[str]]:
    """Step 3: rotation lab -> contract from the vertical (option, file hint checked against the body,
    or toe->head) and the heading (option, rear->front marker pairs, or the lab's axes without markers)."""
    six = picked.six_lab_m if picked is not None else None
    notes = []
    if up is not None:
        up_vec = parse_axis(up)
    elif session.up_hint is not None:
        up_vec = parse_axis(session.up_hint)
        notes.append(f"vertical axis {session.up_hint} as stated by the file")
        if six is not None:
            # Some exporters write a screen axis that is not the lab's up (a
            # real Qualisys file states -Z for a +Z-up lab): the body decides.
            seen = detect_up_axis(six[:, MARKER_NAMES.index("toe")], six[:, MARKER_NAMES.index("head")])
            if float(np.dot(seen, up_vec)) < 0.5:
                notes[-1] = (
                    f"vertical axis {_axis_name(seen)} detected from the toe->head markers; the file states "
                    f"{session.up_hint} (POINT:Y_SCREEN), which would put the head below the feet: ignored"
                )
                up_vec = seen
    elif six is not None:
        up_vec = detect_up_axis(six[:, MARKER_NAMES.index("toe")], six[:, MARKER_NAMES.index("head")])
        notes.append(f"vertical axis {_axis_name(up_vec)} detected from the toe->head markers")
    else:
        raise ValueError("the vertical axis is unknown: give it (--up +Z)")
    if forward is not None:
        fwd = parse_axis(forward)
    elif picked is not None and mapping is not None:
        rear, front = forward_pair_positions(picked.labels, picked.positions_m, mapping)
        fwd = detect_forward(rear, front, up_vec)
        notes.append(f"subject faces lab {_vector_text(fwd)} (detected from {len(rear)} rear->front marker pair(s))")
    else:
        # Force-only: the heading is irrelevant for vertical analysis; keep the lab's axes.
        fwd = next(parse_axis(a) for a in ("+X", "+Y", "+Z") if abs(np.dot(parse_axis(a), up_vec)) < 0.5)
        notes.append(f"no markers: forward taken as lab {_axis_name(fwd)} (give --forward to change it)")
    return rotation_to_contract(up_vec, fwd), notes


def _axis_name(v: np.ndarray) -> str:
    k = int(np.argmax(np.abs(v)))
    return ("+" if v[k] > 0 else "-") + "XYZ"[k]


def _vector_text(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{c:+.3f}" for c in v) + ")"


#: Drillis & Contini (1966) segment proportions (as drawn in Winter 2009, Fig. 4.1):
#: hip (greater trochanter) at 0.530 H, knee at 0.285 H, ankle at 0.039 H above the floor.
LEG_LENGTH_FRACTION = 0.530 - 0.039


def estimate_height_from_leg(six_m: np.ndarray) -> float:
    """Stature (m) from the ankle->knee + knee->hip marker distances.

    Segment lengths do not change with posture, so any trial will do:
    H = (median |knee - ankle| + median |hip - knee|) / 0.491
    (Drillis & Contini 1966 proportions).

    Parameters
    ----------
    six_m : ndarray, shape (M, 6, 3)
        Contract markers (m), :data:`MARKER_NAMES` order.

    Raises
    ------
    ValueError
        If no frame has the ankle, knee and hip markers.
    """
    ankle, knee, hip = (six_m[:, MARKER_NAMES.index(n)] for n in ("ankle", "knee", "hip"))
    shank = np.linalg.norm(knee - ankle, axis=1)
    thigh = np.linalg.norm(hip - knee, axis=1)
    if not (np.isfinite(shank).any() and np.isfinite(thigh).any()):
        raise ValueError("cannot estimate the height: no frame has the ankle, knee and hip markers; give --height-m")
    return float((np.nanmedian(shank) + np.nanmedian(thigh)) / LEG_LENGTH_FRACTION)


def session_to_recording(
    session: LabSession,
    mapping: MarkerMapping | None,
    *,
    up: str | None = None,
    forward: str | None = None,
    mass_kg: float | str | None = None,
    height_m: float | None = None,
    plates: list[int] | None = None,
    sex: str = "female",
    frame_out: dict | None = None,
) -> Recording:
    """Map a lab session to a contract recording (the module docstring's steps 1-5, in order).

    Parameters
    ----------
    session : LabSession
    mapping : MarkerMapping or None
        Needed when the session has markers.
    up, forward : str, optional
        Signed lab axes (``"+Y"``) overriding the file's hint and the detection.
    mass_kg : float or ``"auto"``, optional
        Overrides the file. ``"auto"`` estimates it from quiet standing on the plates (with a
        warning). Without it and without a file value the import fails with a clear message.
    height_m : float, optional
        Overrides the file; otherwise the file's value, else an estimate from the leg markers
        (:func:`estimate_height_from_leg`, with a warning).
    plates : list of int, optional
        0-based plates to use; default all, summed.
    sex : str
        For the de Leva tables.
    frame_out : dict, optional
        Filled with ``rotation`` (lab -> contract, 3x3) and ``origin`` (m, lab) so that a caller can
        express each plate in the same frame (:mod:`hop_impedance.importers.bilateral_import`).

    Returns
    -------
    Recording
        Contract frame (x forward, y left, z up), origin on the ground at the plates' common origin,
        SI units; ``warnings`` says what was detected or estimated.

    Raises
    ------
    ValueError
        Missing markers (named), no force plate, inconsistent rates, unknown mass or height, unknown axes.
    """
    warnings = list(session.warnings)
    chosen = _chosen_plates(session, plates, warnings)
    picked = _pick_contract_markers(session, mapping, sex, warnings) if session.marker_positions_m is not None else None
    rotation, notes = _resolve_axes(session, mapping, picked, up, forward)
    warnings += notes
    origin = session.origin_m if session.origin_m is not None else _ground_origin(chosen, rotation)
    if frame_out is not None:
        frame_out.update(rotation=rotation, origin=np.asarray(origin, float))
    force, moment = _reaction_on_subject(chosen, rotation, origin, warnings)
    markers = None if picked is None else _markers_on_the_ground(session, picked, rotation, origin, mapping, warnings)
    mass = _resolve_mass(mass_kg, session, force[:, 2], warnings)  # step 5: mass, then height
    subject = Subject(session.subject_id or "unknown", mass, _resolve_height(height_m, session, markers, warnings), sex)
    stamps_ns = _stamps_ns(session.force_time_s)
    return Recording(ForcePlateSeries(stamps_ns, force, moment), markers, subject, session.source, warnings)


def _chosen_plates(session: LabSession, plates: list[int] | None, warnings: list[str]) -> list[PlateData]:
    """Step 1 for the plates: the plates to sum (all by default), their one constant rate checked."""
    if not session.plates:
        raise ValueError(f"{session.source or 'session'}: no force plate found")
    chosen = session.plates if plates is None else [session.plates[i] for i in _check_plates(plates, len(session.plates))]
    force_rate = sampling_rate_hz(session.force_time_s, "force plate")
    if (w := _rate_warning(force_rate, CONTRACT_FORCE_RATE_HZ, "force")) is not None:
        warnings.append(w + ": stance edges are only known to one sample")
    return chosen


@dataclass
class _PickedMarkers:
    """The session's markers with the mapping's virtual markers appended, and the contract's six."""

    labels: list[str]
    #: all markers incl. virtual ones, shape (M, L, 3) (m, lab axes)
    positions_m: np.ndarray
    #: the contract's six, :data:`MARKER_NAMES` order, shape (M, 6, 3) (m, lab axes)
    six_lab_m: np.ndarray


def _pick_contract_markers(
    session: LabSession, mapping: MarkerMapping | None, sex: str, warnings: list[str]
) -> _PickedMarkers:
    """Steps 1-2 for the markers: constant rate, virtual markers, the six picked by the mapping, with
    notes on which label or rule fed each, how the streams overlap and how much is occluded."""
    if mapping is None:
        raise ValueError("the session has markers: a marker mapping is needed (--markers NAME or YAML)")
    assert session.marker_time_s is not None and session.marker_positions_m is not None  # they come together
    marker_rate = sampling_rate_hz(session.marker_time_s, "markers")
    if (w := _rate_warning(marker_rate, CONTRACT_MARKER_RATE_HZ, "marker")) is not None:
        warnings.append(w)
    labels, positions, virtual_notes = with_virtual_markers(
        session.marker_labels, session.marker_positions_m, mapping, session.parameters, sex
    )
    six = contract_markers(labels, positions, mapping)
    warnings += [f"marker map {mapping.name}: {line}" for line in source_notes(labels, mapping, virtual_notes)]
    _check_overlap(session.marker_time_s, session.force_time_s, warnings)
    missing = np.isnan(six).any(axis=2).mean(axis=0)
    for name, frac in zip(MARKER_NAMES, missing):
        if frac > 0:
            warnings.append(f"marker {name}: {100 * frac:.1f} % of frames occluded (NaN)")
    return _PickedMarkers(labels, positions, six)


def _reaction_on_subject(
    chosen: list[PlateData], rotation: np.ndarray, origin: np.ndarray, warnings: list[str]
) -> tuple[np.ndarray, np.ndarray]:
    """Step 4: the plates' wrenches in contract axes summed about the contract origin, as the reaction
    on the subject (force N, moment N m)."""
    f = np.stack([to_contract(p.force_n, rotation) for p in chosen])
    m = np.stack([to_contract(p.moment_nm, rotation) for p in chosen])
    r = np.stack([np.broadcast_to(to_contract(p.point_m, rotation, origin), p.force_n.shape) for p in chosen])
    force, moment = total_wrench(f, m, r, np.zeros(3))
    force, moment, flipped = orient_reaction(force, moment)
    if flipped:
        warnings.append("plates gave the force on the plate (vertical down): negated to the reaction on the subject")
    return force, moment


def _markers_on_the_ground(
    session: LabSession,
    picked: _PickedMarkers,
    rotation: np.ndarray,
    origin: np.ndarray,
    mapping: MarkerMapping | None,
    warnings: list[str],
) -> MarkerSeries:
    """The six markers in the contract frame, the mapping's shoe markers lowered to the sole."""
    assert mapping is not None and session.marker_time_s is not None  # markers are picked only with both
    six_c = to_contract(picked.six_lab_m, rotation, origin)
    for name in mapping.lower_to_sole:
        drop = lower_to_sole(six_c, name)
        warnings.append(
            f"marker {name} lowered by {1e3 * drop:.1f} mm to the sole (its height above the plate in flat stance)"
            if drop > 0
            else f"marker {name} not lowered to the sole: it goes below the plates' surface (floor not at plate level?)"
        )
    return MarkerSeries(_stamps_ns(session.marker_time_s), MARKER_NAMES, six_c)

#: Percentile of a foot marker's height taken as its height in flat stance.
SOLE_PERCENTILE = 5.0


def lower_to_sole(six_contract_m: np.ndarray, name: str) -> float:
    """Move one contract marker down to the sole, in place; returns the drop (m).

    A marker on the shoe (e.g. on the 5th metatarsal head) sits some
    centimetres above the sole that touches the ground. In flat stance that
    height is its height above the plate surface (contract z = 0), which is
    the low end of its z over the trial: the drop is the 5th percentile of its
    z (not the minimum, which one bad frame would set). Applied along the
    vertical, so when the foot tilts by phi the point is off by h (1 - cos phi)
    (under 1 mm for h = 3 cm up to 14 degrees).
    """
    k = MARKER_NAMES.index(name)
    z = six_contract_m[:, k, 2]
    if not np.isfinite(z).any():
        return 0.0
    drop = float(np.nanpercentile(z, SOLE_PERCENTILE))
    if drop <= 0:
        return 0.0
    six_contract_m[:, k, 2] -= drop
    return drop


def _check_plates(plates: list[int], n: int) -> list[int]:
    bad = [i for i in plates if not 0 <= i < n]
    if bad:
        raise ValueError(f"plate(s) {bad} do not exist: the file has {n} plate(s), numbered from 0")
    return plates


def _check_overlap(marker_t: np.ndarray, force_t: np.ndarray, warnings: list[str]) -> None:
    gap = max(abs(marker_t[0] - force_t[0]), abs(marker_t[-1] - force_t[-1]))
    if gap > 0.1:
        warnings.append(
            f"markers span {marker_t[0]:.3f}-{marker_t[-1]:.3f} s but forces {force_t[0]:.3f}-{force_t[-1]:.3f} s"
        )


def _resolve_mass(mass_kg: float | str | None, session: LabSession, fz: np.ndarray, warnings: list[str]) -> float:
    if mass_kg == "auto":
        est, start = estimate_mass_from_quiet_stance(session.force_time_s, fz)
        warnings.append(f"body mass {est:.1f} kg estimated from quiet standing at {start:.2f} s (mean Fz / g)")
        return est
    if mass_kg is not None:
        value = float(mass_kg)
    elif session.body_mass_kg is not None:
        value = float(session.body_mass_kg)
    else:
        raise ValueError(
            "body mass unknown: the file does not give it; pass --mass-kg KG (or --mass-kg auto to estimate it "
            "from quiet standing on the plates)"
        )
    if not 10.0 <= value <= 300.0:
        raise ValueError(f"body mass {value:g} kg is implausible (expected 10-300 kg)")
    return value


def _resolve_height(
    height_m: float | None,
    session: LabSession,
    markers: MarkerSeries | None,
    warnings: list[str],
) -> float:
    if height_m is not None:
        value = float(height_m)
    elif session.body_height_m is not None:
        value = float(session.body_height_m)
    elif markers is not None:
        value = estimate_height_from_leg(markers.positions_m)
        warnings.append(
            f"body height {value:.2f} m estimated from the shank + thigh marker lengths (0.491 of stature, "
            "Drillis & Contini 1966); pass --height-m to set it"
        )
    else:
        raise ValueError("body height unknown: the file does not give it; pass --height-m M")
    if not 0.5 <= value <= 2.5:
        raise ValueError(f"body height {value:g} m is implausible (expected 0.5-2.5 m)")
    return value
