"""Force-only text files (time, vertical GRF) -> contract recording without markers.

For sessions recorded on a force plate alone, e.g. ``bmc_cmj_grf/jump1.txt``
(header ``Time[s]\\tGRF[N]``, 450 Hz). The recording carries the vertical
force only: Fx = Fy = 0 (not measured), torque = 0, so the centre of pressure
is undefined (the contract's ``cop_x = -torque.y / force.z`` gives 0, which is
*not* a measurement; see :data:`FORCE_ONLY_LIMITS`). Stance detection, contact
and flight times, peak forces, impulse and the centre-of-mass path from the
force (hence leg stiffness) still work.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hop_impedance.importers.session import estimate_mass_from_quiet_stance, sampling_rate_hz
from hop_impedance.recording import ForcePlateSeries, Recording, Subject

#: What cannot be computed without markers; shown by the CLI and kept in ``Recording.warnings``.
FORCE_ONLY_LIMITS = (
    "force only (no markers): stances, contact/flight times, peak force, impulse, centre-of-mass path and leg "
    "stiffness can be computed; joint angles, joint moments, joint powers and joint impedance (stiffness/damping) "
    "cannot, and the centre of pressure is undefined (torque written as 0)"
)

#: Stature (m) written when none is known: de Leva's (1996) female reference subject. Unused without markers.
UNKNOWN_HEIGHT_M = 1.735


def read_force_text(path: str | Path, rate_hz: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Read a (time, vertical force) text file, or one force column with ``rate_hz``.

    Parameters
    ----------
    path : str or Path
        Whitespace/tab/comma separated; an optional non-numeric header line.
    rate_hz : float, optional
        Needed (only) for a single-column file; checked against the time
        column otherwise.

    Returns
    -------
    time_s : ndarray, shape (N,)
    fz_n : ndarray, shape (N,)
        As in the file (N); NaN rows are refused.

    Raises
    ------
    ValueError
        Wrong column count, NaN values, no rate, or a rate that disagrees.
    """
    path = Path(path)
    text = path.read_text(encoding="utf-8", errors="replace").replace(",", " ").splitlines()
    rows = [ln.split() for ln in text if ln.strip()]
    if rows and not _numeric(rows[0]):
        rows = rows[1:]
    if len(rows) < 2:
        raise ValueError(f"{path}: fewer than 2 data rows")
    widths = {len(r) for r in rows}
    if widths not in ({1}, {2}):
        raise ValueError(f"{path}: expected 1 (force) or 2 (time, force) columns, found {sorted(widths)}")
    data = np.asarray(rows, float)
    if np.isnan(data).any():
        raise ValueError(f"{path}: {int(np.isnan(data).any(axis=1).sum())} row(s) hold NaN")
    if data.shape[1] == 1:
        if rate_hz is None:
            raise ValueError(f"{path}: one column (force) and no time: give the sampling rate (--rate-hz)")
        return np.arange(len(data)) / float(rate_hz), data[:, 0]
    time_s = data[:, 0]
    rate = sampling_rate_hz(time_s, f"{path.name} time column")
    if rate_hz is not None and abs(rate - rate_hz) > 0.01 * rate_hz:
        raise ValueError(f"{path}: inconsistent rates: --rate-hz {rate_hz:g} but the time column runs at {rate:.4g} Hz")
    return time_s, data[:, 1]


def _numeric(cells: list[str]) -> bool:
    try:
        [float(c) for c in cells]
    except ValueError:
        return False
    return True


def import_force_only(
    path: str | Path,
    *,
    mass_kg: float | None = None,
    height_m: float | None = None,
    rate_hz: float | None = None,
    subject_id: str | None = None,
    sex: str = "female",
) -> Recording:
    """Contract recording (``markers=None``) from a vertical-force text file.

    Parameters
    ----------
    path : str or Path
    mass_kg : float, optional
        Body mass; estimated from the steadiest second of quiet standing
        (mean Fz / g) when not given, with a warning.
    height_m : float, optional
        Body height; without markers it is not used, so when unknown the
        de Leva reference stature :data:`UNKNOWN_HEIGHT_M` is written, with a warning.
    rate_hz : float, optional
        See :func:`read_force_text`.
    subject_id : str, optional
        Default: the file name's stem.
    sex : str

    Returns
    -------
    Recording
        force_n (N, 3) = (0, 0, Fz) on the subject, z up; torque zero;
        markers None; ``warnings`` starts with :data:`FORCE_ONLY_LIMITS`.

    Raises
    ------
    ValueError
        See :func:`read_force_text`; also when the force is mostly negative
        (sign) or no quiet standing allows a mass estimate.
    """
    time_s, fz = read_force_text(path, rate_hz)
    warnings = [FORCE_ONLY_LIMITS]
    loaded = np.abs(fz) > 20.0
    if loaded.any() and np.median(fz[loaded]) < 0:
        fz = -fz
        warnings.append("vertical force was mostly negative (force on the plate): negated to the reaction on the subject")
    if mass_kg is None:
        mass_kg, start = estimate_mass_from_quiet_stance(time_s, fz)
        warnings.append(f"body mass {mass_kg:.1f} kg estimated from quiet standing at {start:.2f} s (mean Fz / g)")
    if height_m is None:
        height_m = UNKNOWN_HEIGHT_M
        warnings.append(f"body height unknown: {UNKNOWN_HEIGHT_M} m written (de Leva reference; unused without markers)")
    force = np.zeros((fz.size, 3))
    force[:, 2] = fz
    stamps = np.round(time_s * 1e9).astype(np.int64)
    subject = Subject(subject_id or Path(path).stem, float(mass_kg), float(height_m), sex)
    return Recording(ForcePlateSeries(stamps, force, np.zeros_like(force)), None, subject, str(path), warnings)
