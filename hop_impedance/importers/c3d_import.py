"""C3D sessions (Vicon, Qualisys, Motion Analysis) -> lab session, through ezc3d.

The file is read with ``ezc3d.c3d(path, extract_forceplat_data=True)``; no C3D
parsing happens here. ezc3d turns each plate's analog channels (types 1-4,
calibration matrix applied for type 4) into force, moment and centre of
pressure in the *lab* axes; its moment is about the plate's top-surface centre
(the mean of its four ``FORCE_PLATFORM:CORNERS``; ezc3d adds
``F x ORIGIN`` to the transducer moment). This module only converts units,
reads labels, rates and subject parameters, and hands a :class:`LabSession`
to :func:`~hop_impedance.importers.session.session_to_recording`.

Which way the force points (on the plate, as Vicon and AMTI channels give it,
or on the subject) is left to :func:`~hop_impedance.importers.plates.orient_reaction`.
The vertical axis is read from ``POINT:Y_SCREEN`` when the file has it (the
axis drawn upwards on screen, e.g. ``+Z`` for Vicon Nexus, ``+Y`` for some
Motion Analysis exports), else detected from the markers.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hop_impedance.importers.marker_mapping import MarkerMapping, choose_mapping
from hop_impedance.importers.session import LabSession, PlateData, session_to_recording
from hop_impedance.recording import Recording

#: Unit strings found in C3D files (normalised: lower case, no spaces, dots or '*'), to SI.
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2}
FORCE_UNITS = {"n": 1.0, "kn": 1e3}
MOMENT_UNITS = {"nm": 1.0, "nmm": 1e-3, "ncm": 1e-2, "knm": 1e3}

#: Parameter names (group, name) holding the subject's mass (kg) and height, by vendor habit.
MASS_PARAMETERS = (("PROCESSING", "BODYMASS"), ("PROCESSING", "MASS"), ("SUBJECTS", "MASS"), ("SUBJECT", "MASS"))
HEIGHT_PARAMETERS = (("PROCESSING", "HEIGHT"), ("SUBJECTS", "HEIGHT"), ("SUBJECT", "HEIGHT"))


def unit_scale(unit: str, table: dict[str, float], what: str) -> float:
    """SI factor of a unit string (``"Nmm"`` -> 1e-3), or a clear error naming it."""
    key = str(unit).strip().lower().replace(" ", "").replace(".", "").replace("*", "").replace("·", "")
    if key not in table:
        raise ValueError(f"unknown {what} unit {unit!r}; known: {', '.join(table)}")
    return table[key]


def _parameter(params, group: str, name: str):
    """A parameter's value array, matching group and name case-insensitively; None if absent."""
    for g in params.keys():
        if g.upper() != group:
            continue
        for n, p in params[g].items():
            if n.upper() == name and isinstance(p, dict) and len(p.get("value", [])):
                return p["value"]
    return None


def _labels(params) -> list[str]:
    """POINT:LABELS followed by LABELS2, LABELS3 ... (C3D's 255-label overflow)."""
    labels = list(_parameter(params, "POINT", "LABELS") or [])
    k = 2
    while (more := _parameter(params, "POINT", f"LABELS{k}")) is not None:
        labels += list(more)
        k += 1
    return [str(x).strip() for x in labels]


def _subject_values(params, warnings: list[str]) -> tuple[float | None, float | None, str]:
    mass = next((v for g, n in MASS_PARAMETERS if (v := _parameter(params, g, n)) is not None), None)
    height = next((v for g, n in HEIGHT_PARAMETERS if (v := _parameter(params, g, n)) is not None), None)
    names = _parameter(params, "SUBJECTS", "NAMES")
    mass_kg = float(mass[0]) if mass is not None and float(mass[0]) > 0 else None
    height_m = None
    if height is not None and float(height[0]) > 0:
        h = float(height[0])
        # Vicon stores the height in mm; a value above 3 cannot be metres.
        height_m = h / 1000.0 if h > 3.0 else h
        if h > 3.0:
            warnings.append(f"subject height parameter {h:g} read as mm")
    return mass_kg, height_m, str(names[0]).strip() if names is not None else ""


def _processing_parameters(params) -> dict[str, float]:
    """Numeric scalar parameters of the PROCESSING group (Vicon's subject measurements, mm), by name."""
    group: dict = next((params[g] for g in params.keys() if g.upper() == "PROCESSING"), {})
    out = {}
    for name, p in group.items():
        value = p.get("value", []) if isinstance(p, dict) else []
        if len(value) == 1 and isinstance(value[0], (int, float, np.number)):
            out[name] = float(value[0])
    return out


def _markers(c3d, warnings: list[str]) -> tuple[np.ndarray | None, tuple[str, ...], np.ndarray | None]:
    params = c3d["parameters"]
    points = np.asarray(c3d["data"]["points"], float)
    if points.size == 0 or points.shape[1] == 0:
        return None, (), None
    labels = _labels(params)
    if len(labels) != points.shape[1]:
        raise ValueError(f"POINT:LABELS names {len(labels)} markers but the file holds {points.shape[1]}")
    unit = _parameter(params, "POINT", "UNITS")
    if unit is None:
        warnings.append("POINT:UNITS missing: marker positions taken as mm")
    pos = points[:3].transpose(2, 1, 0) * unit_scale(unit[0] if unit is not None else "mm", LENGTH_UNITS, "marker")
    residuals = np.asarray(c3d["data"]["meta_points"]["residuals"], float)
    invalid = np.zeros(pos.shape[:2], bool)
    if residuals.size:
        invalid |= residuals[0].T < 0
    # Several systems (Motion Analysis, older Vicon) write (0, 0, 0) for a gap.
    invalid |= np.all(pos == 0.0, axis=2)
    pos[invalid] = np.nan
    rate = float(c3d["header"]["points"]["frame_rate"])
    first = int(c3d["header"]["points"]["first_frame"])
    time_s = (first + np.arange(pos.shape[0])) / rate
    return time_s, tuple(labels), pos


def _plates(c3d) -> tuple[np.ndarray, list[PlateData]]:
    platforms = c3d["data"]["platform"] if "platform" in c3d["data"].keys() else []
    plates = []
    for i, pf in enumerate(platforms):
        f_scale = unit_scale(pf["unit_force"], FORCE_UNITS, f"plate {i} force")
        m_scale = unit_scale(pf["unit_moment"], MOMENT_UNITS, f"plate {i} moment")
        p_scale = unit_scale(pf["unit_position"], LENGTH_UNITS, f"plate {i} position")
        centre = np.asarray(pf["corners"], float).mean(axis=1) * p_scale
        plates.append(
            PlateData(
                np.asarray(pf["force"], float).T * f_scale,
                np.asarray(pf["moment"], float).T * m_scale,
                centre,
                f"plate {i}",
            )
        )
    rate = float(c3d["header"]["analogs"]["frame_rate"])
    n = plates[0].force_n.shape[0] if plates else 0
    first = int(c3d["header"]["points"]["first_frame"]) / max(float(c3d["header"]["points"]["frame_rate"]), 1e-12)
    return first + np.arange(n) / rate if rate > 0 else np.arange(n, dtype=float), plates


def c3d_session(path: str | Path) -> LabSession:
    """Read a C3D file with ezc3d into a lab session (lab axes, SI units).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    LabSession
        All markers with their labels (NaN where the residual is negative or
        the position is exactly zero), every plate's force and moment about
        its top-surface centre (lab axes), the first plate's centre as the
        common origin, the vertical from ``POINT:Y_SCREEN``, subject mass and
        height from ``PROCESSING``/``SUBJECTS`` parameters when present.

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    ValueError
        If ezc3d cannot read it, its force-plate parameters are unusable,
        a unit is unknown, or there is no force plate.
    """
    path = Path(path)
    c3d = _read_c3d(path)
    warnings: list[str] = []
    params = c3d["parameters"]
    time_s, labels, positions = _markers(c3d, warnings)
    force_time_s, plates = _plates(c3d)
    if not plates:
        raise ValueError(f"{path}: no force plate found (FORCE_PLATFORM:USED is 0 or the group is missing)")
    if time_s is not None and plates:
        _check_rate_ratio(path, c3d)
    up_hint = _up_hint(params, warnings)
    mass, height, subject_id = _subject_values(params, warnings)
    return LabSession(
        marker_time_s=time_s,
        marker_labels=labels,
        marker_positions_m=positions,
        force_time_s=force_time_s,
        plates=plates,
        origin_m=plates[0].point_m,
        up_hint=up_hint,
        body_mass_kg=mass,
        body_height_m=height,
        subject_id=subject_id or path.stem,
        source=str(path),
        warnings=warnings,
        parameters=_processing_parameters(params),
    )


def _read_c3d(path: Path):
    """The file read by ezc3d with its force plates extracted; a clear ValueError naming why not."""
    import ezc3d

    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    try:
        return ezc3d.c3d(str(path), extract_forceplat_data=True)
    except (RuntimeError, ValueError, IndexError, OSError) as exc:
        try:
            ezc3d.c3d(str(path))
        except (RuntimeError, ValueError, IndexError, OSError) as exc2:
            raise ValueError(f"{path}: ezc3d cannot read it: {exc2}") from None
        raise ValueError(f"{path}: force-plate parameters (FORCE_PLATFORM group) are unusable: {exc}") from None


def _check_rate_ratio(path: Path, c3d) -> None:
    """Markers and plates share C3D frames: the analog rate must be an integer multiple of the point rate."""
    ratio = c3d["header"]["analogs"]["frame_rate"] / c3d["header"]["points"]["frame_rate"]
    if abs(ratio - round(ratio)) > 1e-6:
        raise ValueError(f"{path}: inconsistent rates: analog rate / point rate = {ratio:g} is not an integer")


def _up_hint(params, warnings: list[str]) -> str | None:
    """The vertical stated by ``POINT:Y_SCREEN`` (``"+Z"``), or None (absent, or not an axis: warned)."""
    y_screen = _parameter(params, "POINT", "Y_SCREEN")
    up_hint = str(y_screen[0]).strip().upper() if y_screen is not None else None
    if up_hint is not None and up_hint.lstrip("+-") not in ("X", "Y", "Z"):
        warnings.append(f"POINT:Y_SCREEN {up_hint!r} is not an axis: vertical detected from the markers")
        up_hint = None
    return up_hint


def import_c3d(path: str | Path, markers: str | Path | MarkerMapping | None = None, **options) -> Recording:
    """Contract recording from a C3D file.

    Parameters
    ----------
    path : str or Path
    markers : mapping name, YAML path, MarkerMapping or None
        None picks the first shipped mapping whose markers are all present.
    **options
        Passed to :func:`~hop_impedance.importers.session.session_to_recording`
        (``up``, ``forward``, ``mass_kg``, ``height_m``, ``plates``, ``sex``).

    Returns
    -------
    Recording
        Contract frame and units; ``warnings`` lists detections and estimates.
    """
    session = c3d_session(path)
    mapping = choose_mapping(session.marker_labels, markers) if session.marker_positions_m is not None else None
    return session_to_recording(session, mapping, **options)
