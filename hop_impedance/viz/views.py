"""Rerun logging functions: one per concern, each taking an explicit ``RecordingStream``.

Bulk signals go through ``rr.send_columns`` (one call per entity for a whole
block of samples); per-stance geometry through ``set_time`` + ``log``. Time is
always the ``time`` duration timeline in seconds since the recording's first
message (from the data's own stamps, never the wall clock). Frames and signs
follow docs/ARCHITECTURE.md; the sagittal picture is x right, z up, drawn with
z negated because Rerun's 2D views point y down.
"""

from __future__ import annotations

import numpy as np
import rerun as rr

from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.recording import MARKER_NAMES
from hop_impedance.viz import style as S
from hop_impedance.viz.chart import Chart, log_chart_frame
from hop_impedance.viz.stance_view import StanceView, fit_table_markdown

_TOE, _HEEL, _ANKLE, _KNEE, _HIP, _HEAD = (MARKER_NAMES.index(n) for n in ("toe", "heel", "ankle", "knee", "hip", "head"))
#: Polylines of the stick figure: the foot triangle and the shank-thigh-HAT chain.
STICK_CHAINS: tuple[tuple[int, ...], ...] = ((_TOE, _HEEL, _ANKLE, _TOE), (_ANKLE, _KNEE, _HIP, _HEAD))


def _time(t_s: np.ndarray) -> rr.TimeColumn:
    return rr.TimeColumn(S.TIMELINE, duration=np.asarray(t_s, float))


def log_static_styles(rec: rr.RecordingStream) -> None:
    """Series names, colours and line styles, body colours and the ground line (all static, logged once)."""
    rec.log(S.GRF_BW, rr.SeriesLines(colors=S.GRF_COLOR, names="vertical GRF (BW)", widths=1.5), static=True)
    rec.log(
        S.IN_STANCE,
        rr.SeriesLines(colors=(120, 120, 120), names="in stance (0/1)", widths=1.0, interpolation_mode="StepAfter"),
        static=True,
    )
    for joint in JOINT_NAMES:
        color = S.JOINT_COLORS[joint]
        for path in (f"{S.ANGLE}/{joint}", f"{S.VELOCITY}/{joint}", f"{S.POWER}/{joint}", f"{S.STIFFNESS}/{joint}"):
            rec.log(path, rr.SeriesLines(colors=color, names=joint, widths=1.5), static=True)
        rec.log(S.moment_path(joint, "inverse_dynamics"), rr.SeriesLines(colors=color, names=f"{joint} ID", widths=2.0),
                static=True)
        rec.log(S.moment_path(joint, "variable_fit"), rr.SeriesLines(colors=S.FIT_COLOR, names=f"{joint} fit", widths=1.0),
                static=True)
        for coef in ("k0", "k1"):
            path = f"{S.TREND}/{coef}/{joint}"
            rec.log(path, rr.SeriesLines(colors=color, names=joint, widths=1.0), static=True)
            rec.log(path, rr.SeriesPoints(colors=color, names=joint, markers="circle", marker_sizes=3.0), static=True)
    rec.log(S.SEGMENTS, rr.LineStrips2D.from_fields(colors=S.SEGMENT_COLOR, radii=-2.0), static=True)
    rec.log(S.MARKERS, rr.Points2D.from_fields(colors=S.MARKER_COLOR, radii=-3.0), static=True)
    rec.log(S.GRF_ARROW, rr.Arrows2D.from_fields(colors=S.GRF_COLOR, radii=-1.5), static=True)
    rec.log(S.GROUND, rr.LineStrips2D([[[-1.0, 0.0], [1.0, 0.0]]], colors=(120, 90, 60), radii=-1.0), static=True)


def _finite_runs(points: np.ndarray) -> list[np.ndarray]:
    """Split a polyline (k, 2) at non-finite points; keep runs of at least two points."""
    ok = np.all(np.isfinite(points), axis=1)
    runs, start = [], None
    for i, good in enumerate(np.append(ok, False)):
        if good and start is None:
            start = i
        elif not good and start is not None:
            if i - start >= 2:
                runs.append(points[start:i])
            start = None
    return runs


def stick_figure_strips(markers_xz: np.ndarray) -> tuple[list[np.ndarray], list[int]]:
    """Line strips of the stick figure in view coordinates (x, -z).

    Parameters
    ----------
    markers_xz : ndarray, shape (M, 6, 2)
        Contract markers (:data:`MARKER_NAMES` order), lab ``[x, z]`` (m); NaN = occluded.

    Returns
    -------
    strips : list of ndarray (k, 2)
        All frames' strips, flattened; an occluded marker splits its chain.
    counts : list of int, length M
        Strips per frame (for ``partition``).
    """
    view = np.asarray(markers_xz, float) * [1.0, -1.0]
    strips, counts = [], []
    for frame in view:
        runs = [r for chain in STICK_CHAINS for r in _finite_runs(frame[list(chain)])]
        strips += runs
        counts.append(len(runs))
    return strips, counts


def log_body(rec: rr.RecordingStream, t_s: np.ndarray, markers_xz: np.ndarray) -> None:
    """Stick figure (segments and markers) at each marker frame, in one columnar call each.

    Parameters
    ----------
    rec : rerun.RecordingStream
    t_s : ndarray, shape (M,)
        Frame times (s since the recording's first message).
    markers_xz : ndarray, shape (M, 6, 2)
        Lab ``[x, z]`` marker positions (m); NaN markers are left out of that frame.
    """
    t_s = np.asarray(t_s, float)
    if t_s.size == 0:
        return
    strips, counts = stick_figure_strips(markers_xz)
    rec.send_columns(
        S.SEGMENTS,
        indexes=[_time(t_s)],
        columns=rr.LineStrips2D.columns(strips=strips).partition(counts),
    )
    flat = np.asarray(markers_xz, float).reshape(-1, 2) * [1.0, -1.0]
    ok = np.all(np.isfinite(flat), axis=1)
    lengths = ok.reshape(len(t_s), -1).sum(axis=1)
    rec.send_columns(S.MARKERS, indexes=[_time(t_s)], columns=rr.Points2D.columns(positions=flat[ok]).partition(lengths))


def log_ground_reaction(
    rec: rr.RecordingStream, t_s: np.ndarray, force_xz_n: np.ndarray, cop_x_m: np.ndarray, body_weight_n: float
) -> None:
    """Vertical GRF in body weights, and the GRF arrow at the centre of pressure.

    Parameters
    ----------
    rec : rerun.RecordingStream
    t_s : ndarray, shape (N,)
        Force-plate sample times (s).
    force_xz_n : ndarray, shape (N, 2)
        ``[Fx, Fz]`` on the subject (N), lab frame.
    cop_x_m : ndarray, shape (N,)
        Anterior centre of pressure (m), NaN in flight (Fz below
        :data:`style.MIN_COP_FORCE_N`): no arrow is drawn then.
    body_weight_n : float
        m g (N); arrow length is :data:`style.GRF_ARROW_M_PER_BW` m per BW.
    """
    t_s = np.asarray(t_s, float)
    if t_s.size == 0:
        return
    f = np.asarray(force_xz_n, float)
    rec.send_columns(S.GRF_BW, indexes=[_time(t_s)], columns=rr.Scalars.columns(scalars=f[:, 1] / body_weight_n))
    cop = np.asarray(cop_x_m, float)
    ok = np.isfinite(cop) & np.all(np.isfinite(f), axis=1)
    origins = np.column_stack([cop[ok], np.zeros(ok.sum())])
    vectors = f[ok] * [1.0, -1.0] * (S.GRF_ARROW_M_PER_BW / body_weight_n)
    rec.send_columns(
        S.GRF_ARROW,
        indexes=[_time(t_s)],
        columns=rr.Arrows2D.columns(origins=origins, vectors=vectors).partition(ok.astype(int)),
    )


def cop_x_from_wrench(force_n: np.ndarray, torque_nm: np.ndarray, min_fz_n: float = S.MIN_COP_FORCE_N) -> np.ndarray:
    """Anterior centre of pressure ``-torque_y / force_z`` (m), NaN where Fz < ``min_fz_n``.

    Parameters
    ----------
    force_n, torque_nm : ndarray, shape (N, 3)
        Plate wrench about the plate origin (contract: plate frame = lab frame).
    """
    fz = np.asarray(force_n, float)[:, 2]
    out = np.full(fz.shape, np.nan)
    ok = fz > min_fz_n
    out[ok] = -np.asarray(torque_nm, float)[ok, 1] / fz[ok]
    return out


def log_stance_event(rec: rr.RecordingStream, t_s: float, touchdown: bool) -> None:
    """One stance mark on the GRF plot: the 0/1 step series goes to 1 at a touchdown, 0 at a take-off."""
    rec.send_columns(S.IN_STANCE, indexes=[_time(np.array([t_s]))],
                     columns=rr.Scalars.columns(scalars=[1.0 if touchdown else 0.0]))


def log_stance_interval(rec: rr.RecordingStream, touchdown_s: float, takeoff_s: float) -> None:
    """Mark a stance on the GRF plot (touchdown and take-off, s)."""
    rec.send_columns(S.IN_STANCE, indexes=[_time(np.array([touchdown_s, takeoff_s]))],
                     columns=rr.Scalars.columns(scalars=[1.0, 0.0]))


def log_joint_series(
    rec: rr.RecordingStream,
    t_s: np.ndarray,
    angle_rad: np.ndarray,
    angular_velocity_rad_s: np.ndarray,
    moment_nm: np.ndarray,
    power_w: np.ndarray,
    end_of_stance: bool = True,
) -> None:
    """Joint angles (deg), angular velocities (deg/s), ID moments (N m) and powers (W).

    Parameters
    ----------
    rec : rerun.RecordingStream
    t_s : ndarray, shape (n,)
        Sample times (s since the recording's first message).
    angle_rad, angular_velocity_rad_s, moment_nm, power_w : ndarray, shape (n, 3)
        Columns ankle, knee, hip; conventions of docs/ARCHITECTURE.md.
    end_of_stance : bool
        Append one NaN sample just after the last one so the plotted line
        does not bridge the flight to the next stance.
    """
    t_s = np.asarray(t_s, float)
    if t_s.size == 0:
        return
    blocks = {
        S.ANGLE: np.degrees(angle_rad),
        S.VELOCITY: np.degrees(angular_velocity_rad_s),
        S.MOMENT: np.asarray(moment_nm, float),
        S.POWER: np.asarray(power_w, float),
    }
    if end_of_stance:
        t_s = np.append(t_s, t_s[-1] + 1e-3)
        blocks = {k: np.vstack([v, np.full((1, 3), np.nan)]) for k, v in blocks.items()}
    for root, values in blocks.items():
        for j, joint in enumerate(JOINT_NAMES):
            path = S.moment_path(joint, "inverse_dynamics") if root == S.MOMENT else f"{root}/{joint}"
            rec.send_columns(path, indexes=[_time(t_s)], columns=rr.Scalars.columns(scalars=values[:, j]))


def joint_charts(angle_deg_ranges: dict, moment_ranges: dict, stiffness_ranges: dict) -> dict[str, tuple[Chart, Chart]]:
    """Moment-angle and K(rho) charts per joint, side by side in one view.

    Parameters
    ----------
    angle_deg_ranges, moment_ranges, stiffness_ranges : dict
        ``joint -> (lo, hi)`` in deg, N m and N m/rad.

    Returns
    -------
    dict
        ``joint -> (loop_chart, stiffness_chart)``.
    """
    out = {}
    for joint in JOINT_NAMES:
        loop = Chart(angle_deg_ranges[joint], moment_ranges[joint], "rho (deg, flexion +)", "M (N m)")
        k = Chart(angle_deg_ranges[joint], stiffness_ranges[joint], "rho (deg, flexion +)", "K (N m/rad)", left=130.0)
        out[joint] = (loop, k)
    return out


#: Ranges used live before any data are known (deg, N m, N m/rad): seed-typical hopping.
DEFAULT_CHART_RANGES = (
    {"ankle": (70.0, 150.0), "knee": (190.0, 280.0), "hip": (150.0, 240.0)},
    {"ankle": (-20.0, 350.0), "knee": (-50.0, 300.0), "hip": (-80.0, 200.0)},
    {"ankle": (0.0, 800.0), "knee": (0.0, 800.0), "hip": (0.0, 600.0)},
)


def log_chart_frames(rec: rr.RecordingStream, charts: dict[str, tuple[Chart, Chart]]) -> None:
    """Axes and titles of every joint's two charts (static)."""
    for joint, (loop, k) in charts.items():
        log_chart_frame(rec, S.chart_path(joint, "loop", "frame"), loop, f"{joint}: moment-angle loop")
        log_chart_frame(rec, S.chart_path(joint, "k_rho", "frame"), k, f"{joint}: K(rho)")


def _strip(rec, path, points, color, width_ui, draw_order) -> None:
    pts = points[np.all(np.isfinite(points), axis=1)]
    rec.log(path, rr.LineStrips2D([pts], colors=color, radii=-width_ui, draw_order=draw_order))


def log_stance(rec: rr.RecordingStream, view: StanceView, charts: dict[str, tuple[Chart, Chart]]) -> None:
    """Everything of one stance, logged at its take-off (and at ``stance`` = its index).

    Logs the fit table (markdown) and an event-log line; per accepted joint
    the fitted moment and K(t) on the time axis, the moment-angle loop with
    the variable and constant stiffness fits and the K(rho) curve (``current``
    entities replaced stance by stance; a grey copy kept under ``history``),
    and k0, k1 on the trend plots. A rejected stance or joint logs its reason
    (table and log) and no numbers.

    Parameters
    ----------
    rec : rerun.RecordingStream
    view : StanceView
    charts : dict
        From :func:`joint_charts`.
    """
    rec.set_time(S.TIMELINE, duration=view.takeoff_s)
    rec.set_time(S.STANCE_TIMELINE, sequence=view.index)
    rec.log(S.TABLE, rr.TextDocument(fit_table_markdown(view), media_type=rr.MediaType.MARKDOWN))
    reasons = [view.rejection_reason] if view.rejection_reason else [
        f"{j}: {v.rejection_reason}" for j, v in view.joints.items() if not v.ok
    ]
    level = rr.TextLogLevel.WARN if reasons else rr.TextLogLevel.INFO
    text = f"stance {view.index} {view.touchdown_s:.3f}-{view.takeoff_s:.3f} s: " + ("; ".join(reasons) or "fitted")
    rec.log(S.EVENT_LOG, rr.TextLog(text, level=level))
    for joint, j in view.joints.items():
        for coef in ("k0", "k1"):
            rec.log(f"{S.TREND}/{coef}/{joint}", rr.Scalars(j.coefficient(coef)))
        if j.ok:
            _log_joint_fit(rec, view, joint, j, charts[joint])
    rec.reset_time()


def _log_joint_fit(rec, view: StanceView, joint: str, j, charts: tuple[Chart, Chart]) -> None:
    t = view.touchdown_s + np.append(j.time_s, j.time_s[-1] + 1e-3)
    gap = np.full(1, np.nan)
    rec.send_columns(S.moment_path(joint, "variable_fit"), indexes=[_time(t)],
                     columns=rr.Scalars.columns(scalars=np.append(j.moment_fit_nm, gap)))
    rec.send_columns(f"{S.STIFFNESS}/{joint}", indexes=[_time(t)],
                     columns=rr.Scalars.columns(scalars=np.append(j.stiffness_nm_per_rad, gap)))
    loop, kc = charts
    deg = np.degrees(j.angle_rad)
    color = S.JOINT_COLORS[joint]
    measured = loop.to_view(deg, j.moment_nm)
    _strip(rec, S.chart_path(joint, "loop", "current", "measured"), measured, color, 2.0, 3.0)
    _strip(rec, S.chart_path(joint, "loop", "current", "variable_fit"), loop.to_view(deg, j.moment_fit_nm), S.FIT_COLOR, 1.0, 4.0)
    _strip(rec, S.chart_path(joint, "loop", "current", "constant_fit"), loop.to_view(deg, j.moment_constant_nm),
           S.CONSTANT_COLOR, 1.0, 4.0)
    k_rho = kc.to_view(deg, j.stiffness_nm_per_rad)
    _strip(rec, S.chart_path(joint, "k_rho", "current"), k_rho, color, 2.0, 3.0)
    _strip(rec, S.chart_path(joint, "loop", "history", f"stance_{view.index:03d}"), measured, S.HISTORY_COLOR, 0.5, 2.0)
    _strip(rec, S.chart_path(joint, "k_rho", "history", f"stance_{view.index:03d}"), k_rho, S.HISTORY_COLOR, 0.5, 2.0)
