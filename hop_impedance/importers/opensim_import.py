"""OpenSim TRC (markers) and MOT (ground reaction forces) files -> lab session.

Both are small tab-separated text formats, parsed here with numpy:

- TRC: line 1 ``PathFileType``, line 2 header keys, line 3 their values
  (``DataRate``, ``NumMarkers``, ``Units`` ...), line 4 ``Frame# Time`` and
  one label per marker (each followed by two empty cells), line 5 ``X1 Y1
  Z1 ...``, then data rows. An occluded marker is an empty cell (NaN here).
- MOT (OpenSim storage): free-form header up to ``endheader``, a line of
  column names, then data rows. Force plates are recognised by column names:
  ``<prefix>force<suffix>_v{x,y,z}`` (force), ``..._p{x,y,z}`` (point of
  application = centre of pressure) and ``..._m{x,y,z}`` or
  ``<prefix>torque<suffix>_{x,y,z}`` (torque about that point), e.g.
  ``ground_force_1_vx`` / ``ground_force_1_px`` / ``ground_force_1_mx`` or
  ``ground_force_vx`` / ``ground_torque_x``. OpenSim files are SI (N, m, N m)
  with y up.

Real exporters vary (OpenSim, MATLAB tool chains, Vicon Nexus, Motion
Monitor ...), and OpenSim reads all of these, so this reader does too
(``test/importers/test_text_variants.py`` builds each variant from a real file):

- line endings ``\n``, ``\r\n`` or ``\r``; a byte-order mark; blank lines
  anywhere in the header, after ``endheader`` and between data rows;
- cells separated by tabs (empty cell = NaN, trailing tabs ignored) or, in a
  line without tabs, by runs of spaces (fixed-width, padded columns);
- missing values written ``nan``, ``NaN``, ``-nan(ind)``, ``1.#QNAN``,
  ``-1.#IND`` or left empty;
- ``endheader`` in any case with surrounding spaces; ``key=value`` header
  lines with spaces around ``=``; a TRC header whose keys and values are
  separated by spaces.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hop_impedance.importers.marker_mapping import MarkerMapping, choose_mapping
from hop_impedance.importers.session import LabSession, PlateData, sampling_rate_hz, session_to_recording
from hop_impedance.recording import Recording

#: Length units accepted in TRC headers, in metres.
LENGTH_UNITS_M = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "meters": 1.0, "millimeters": 1e-3}

#: OpenSim's convention: y is the vertical axis.
OPENSIM_UP = "+Y"


@dataclass
class TrcData:
    """Markers of a TRC file.

    Attributes
    ----------
    time_s : ndarray, shape (M,)
    labels : tuple of str, length L
    positions_m : ndarray, shape (M, L, 3)
        Lab frame of the file (m); NaN where a cell is empty.
    rate_hz : float
        ``DataRate`` of the header.
    """

    time_s: np.ndarray
    labels: tuple[str, ...]
    positions_m: np.ndarray
    rate_hz: float


@dataclass
class MotData:
    """Columns of an OpenSim storage (.mot/.sto) file.

    Attributes
    ----------
    columns : tuple of str
    values : ndarray, shape (N, len(columns))
    header : dict of str -> str
        ``key=value`` lines of the header.
    """

    columns: tuple[str, ...]
    values: np.ndarray
    header: dict[str, str]

    def column(self, name: str) -> np.ndarray:
        """One column by name, shape (N,)."""
        return self.values[:, self.columns.index(name)]


#: Spellings of a missing value seen in exported text files (lower case), besides an empty cell.
NAN_SPELLINGS = frozenset({"nan", "-nan", "+nan", "nan(ind)", "-nan(ind)", "1.#qnan", "-1.#qnan", "1.#ind", "-1.#ind",
                           "na", "n/a"})


def _lines(path: Path) -> list[str]:
    """Text lines of a file with any line ending (\\n, \\r\\n, \\r), without a UTF-8 byte-order mark."""
    return path.read_text(encoding="utf-8-sig", errors="replace").splitlines()


def split_cells(line: str, width: int | None = None) -> list[str]:
    """Cells of one line: tab-separated (empty cells kept), else whitespace-separated.

    Trailing empty tab cells are dropped beyond ``width`` (all of them when
    ``width`` is None), so a trailing tab is not a value but an empty last
    column still is.
    """
    if "\t" in line:
        cells = [c.strip() for c in line.split("\t")]
        while cells and not cells[-1] and (width is None or len(cells) > width):
            cells.pop()
        return cells
    return line.split()


def _number(cell: str, where: str) -> float:
    text = cell.strip()
    if not text or text.lower() in NAN_SPELLINGS:
        return np.nan
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"{where}: {cell!r} is not a number") from None


def _float_cells(cells: list[str], width: int, where: str) -> list[float]:
    out = [_number(c, where) for c in cells[:width]]
    return out + [np.nan] * (width - len(out))


def read_trc(path: str | Path) -> TrcData:
    """Read an OpenSim TRC marker file.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    TrcData
        Positions converted to metres from the header's ``Units``.

    Raises
    ------
    ValueError
        Malformed header, unknown units, or a ``DataRate`` that disagrees
        with the time column (inconsistent rates).
    """
    path = Path(path)
    lines = [ln for ln in _lines(path) if ln.strip()]
    if len(lines) < 6 or not lines[0].strip().startswith("PathFileType"):
        raise ValueError(f"{path}: not a TRC file (first line must start with 'PathFileType')")
    header = dict(zip(split_cells(lines[1]), split_cells(lines[2])))
    try:
        rate = float(header["DataRate"])
        n_markers = int(float(header["NumMarkers"]))
        units = header["Units"].strip()
    except (KeyError, ValueError) as exc:
        raise ValueError(f"{path}: TRC header lacks a valid {exc} entry (DataRate, NumMarkers, Units)") from None
    if units.lower() not in LENGTH_UNITS_M:
        raise ValueError(f"{path}: unknown TRC length unit {units!r}; expected one of {', '.join(LENGTH_UNITS_M)}")
    labels = tuple(c for c in split_cells(lines[3])[2:] if c)
    if len(labels) != n_markers:
        raise ValueError(f"{path}: header says {n_markers} markers but line 4 names {len(labels)}")
    width = 2 + 3 * n_markers
    # Line 5 names the coordinates (X1 Y1 Z1 ...); some writers leave it out.
    first = 5 if split_cells(lines[4])[:1] and not _is_number(split_cells(lines[4])[0]) else 4
    rows = [_float_cells(split_cells(ln), width, f"{path.name} line {k + 1}") for k, ln in enumerate(lines[first:], first)]
    if len(rows) < 2:
        raise ValueError(f"{path}: fewer than 2 data rows")
    data = np.asarray(rows, float)
    time_s = data[:, 1]
    column_rate = sampling_rate_hz(time_s, f"{path.name} time column")
    if abs(column_rate - rate) > 0.01 * rate:
        raise ValueError(
            f"{path}: inconsistent rates: header DataRate {rate:g} Hz but the time column runs at {column_rate:.4g} Hz"
        )
    positions = data[:, 2:].reshape(len(data), n_markers, 3) * LENGTH_UNITS_M[units.lower()]
    return TrcData(time_s, labels, positions, rate)


def read_mot(path: str | Path) -> MotData:
    """Read an OpenSim storage (.mot/.sto) file: header up to ``endheader``, then named columns.

    Raises
    ------
    ValueError
        If there is no ``endheader`` line or the rows do not match the column names.
    """
    path = Path(path)
    lines = _lines(path)
    try:
        end = next(i for i, ln in enumerate(lines) if ln.strip().lower() == "endheader")
    except StopIteration:
        raise ValueError(f"{path}: not an OpenSim storage file (no 'endheader' line)") from None
    header = {k.strip(): v.strip() for k, _, v in (ln.partition("=") for ln in lines[:end] if "=" in ln)}
    body = [ln for ln in lines[end + 1 :] if ln.strip()]
    if not body:
        raise ValueError(f"{path}: no column names after 'endheader'")
    columns = tuple(c for c in split_cells(body[0]) if c)
    if any(_is_number(c) for c in columns):
        raise ValueError(f"{path}: the first line after 'endheader' must name the columns, found numbers: {body[0][:60]!r}")
    rows = [split_cells(ln, len(columns)) for ln in body[1:]]
    bad = [i for i, r in enumerate(rows) if len(r) != len(columns)]
    if bad:
        raise ValueError(f"{path}: data row {bad[0] + 1} has {len(rows[bad[0]])} values for {len(columns)} columns")
    values = np.array([[_number(c, f"{path.name} data row {i + 1}") for c in r] for i, r in enumerate(rows)], float)
    return MotData(columns, values.reshape(len(rows), len(columns)), header)


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return cell.strip().lower() in NAN_SPELLINGS
    return True


_FORCE_COLUMN = re.compile(r"^(?P<pre>.*)force(?P<suf>.*)_v(?P<ax>[xyz])$")


def mot_plates(mot: MotData) -> list[PlateData]:
    """Force plates found in a GRF storage file, in order of first appearance.

    Returns
    -------
    list of PlateData
        Force, torque about the point of application, and that point (the
        centre of pressure), in the file's axes and SI units.

    Raises
    ------
    ValueError
        If a plate's force has no point-of-application columns.
    """
    keys: list[tuple[str, str]] = []
    for c in mot.columns:
        if (hit := _FORCE_COLUMN.match(c)) and (hit["pre"], hit["suf"]) not in keys:
            keys.append((hit["pre"], hit["suf"]))
    plates = []
    for pre, suf in keys:
        stem = f"{pre}force{suf}"
        force = _triple(mot, [f"{stem}_v{a}" for a in "xyz"], stem)
        point = _triple(mot, [f"{stem}_p{a}" for a in "xyz"], stem, what="point of application (_px/_py/_pz)")
        torque_names = [f"{stem}_m{a}" for a in "xyz"]
        if not all(n in mot.columns for n in torque_names):
            torque_names = [f"{pre}torque{suf}_{a}" for a in "xyz"]
        torque = (
            _triple(mot, torque_names, stem) if all(n in mot.columns for n in torque_names) else np.zeros_like(force)
        )
        plates.append(PlateData(force, torque, point, stem))
    return plates


def _triple(mot: MotData, names: list[str], stem: str, what: str = "columns") -> np.ndarray:
    missing = [n for n in names if n not in mot.columns]
    if missing:
        raise ValueError(f"force {stem!r}: missing {what}: {', '.join(missing)}")
    return np.stack([mot.column(n) for n in names], axis=1)


def opensim_session(trc_path: str | Path | None, mot_path: str | Path) -> LabSession:
    """Lab session from a TRC marker file (optional) and a GRF MOT file.

    Parameters
    ----------
    trc_path : str, Path or None
        None for a force-only session.
    mot_path : str or Path

    Returns
    -------
    LabSession
        Lab axes of the files (OpenSim: y up, stated as the up hint), SI units.

    Raises
    ------
    ValueError
        No force columns in the MOT (no force plate), or inconsistent rates.
    """
    mot = read_mot(mot_path)
    if "time" not in mot.columns:
        raise ValueError(f"{mot_path}: no 'time' column")
    plates = mot_plates(mot)
    if not plates:
        raise ValueError(f"{mot_path}: no force plate found (no '*force*_vx/_vy/_vz' columns)")
    warnings = []
    empty = [p.name for p in plates if not np.any(p.force_n)]
    if empty:
        warnings.append(f"force plate(s) {', '.join(empty)} carry only zeros")
    trc = read_trc(trc_path) if trc_path is not None else None
    return LabSession(
        marker_time_s=None if trc is None else trc.time_s,
        marker_labels=() if trc is None else trc.labels,
        marker_positions_m=None if trc is None else trc.positions_m,
        force_time_s=mot.column("time"),
        plates=plates,
        origin_m=None,
        up_hint=OPENSIM_UP,
        subject_id=Path(trc_path or mot_path).name.split("_")[0],
        source=", ".join(str(p) for p in (trc_path, mot_path) if p is not None),
        warnings=warnings,
    )


def import_opensim(
    trc_path: str | Path | None, mot_path: str | Path, markers: str | Path | MarkerMapping | None = None, **options
) -> Recording:
    """Contract recording from an OpenSim TRC + GRF MOT pair (TRC optional).

    Parameters
    ----------
    trc_path : str, Path or None
    mot_path : str or Path
    markers : mapping name, YAML path, MarkerMapping or None
        None picks the first shipped mapping whose markers are all present.
    **options
        Passed to :func:`~hop_impedance.importers.session.session_to_recording`
        (``up`` defaults to OpenSim's +Y, ``forward``, ``mass_kg``, ``height_m``, ``plates``, ``sex``).

    Returns
    -------
    Recording
    """
    session = opensim_session(trc_path, mot_path)
    mapping = choose_mapping(session.marker_labels, markers) if session.marker_positions_m is not None else None
    return session_to_recording(session, mapping, **options)
