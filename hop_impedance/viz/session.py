"""Offline view of a whole recording: analysis + fits -> the same Rerun entities as live.

Used by ``hop-impedance view REC.mcap [--rrd OUT.rrd]`` and by ``make demo``
(:func:`write_rrd`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import rerun as rr

from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.biomech.kinematics import sagittal_markers
from hop_impedance.recording import Recording
from hop_impedance.viz.analytics import ensure_analytics_disabled
from hop_impedance.viz.blueprint import default_blueprint
from hop_impedance.viz.chart import Chart, padded_range
from hop_impedance.viz.stance_view import StanceView, stance_view_from_result
from hop_impedance.viz.views import (
    DEFAULT_CHART_RANGES,
    cop_x_from_wrench,
    joint_charts,
    log_body,
    log_chart_frames,
    log_ground_reaction,
    log_joint_series,
    log_stance,
    log_stance_interval,
    log_static_styles,
)

APPLICATION_ID = "hop_impedance"


@dataclass
class SessionSummary:
    """What :func:`log_session` logged (for messages and tests)."""

    stances: int
    fitted_stances: int
    rejected: dict[int, str]
    marker_frames: int
    force_samples: int


def stance_views(analysis, fits: list[dict] | None) -> list[StanceView]:
    """One :class:`StanceView` per analysed stance (fits: one ``{joint: fit}`` per stance, or None)."""
    per_stance: list[dict | None] = list(fits) if fits is not None else [None] * len(analysis.stances)
    if len(per_stance) != len(analysis.stances):
        raise ValueError(f"fits: {len(per_stance)} entries for {len(analysis.stances)} stances")
    return [stance_view_from_result(s, f) for s, f in zip(analysis.stances, per_stance)]


def charts_for(views: list[StanceView]) -> dict[str, tuple[Chart, Chart]]:
    """Chart ranges covering every accepted fit (defaults of :data:`DEFAULT_CHART_RANGES` for a joint with none)."""
    ranges = [dict(r) for r in DEFAULT_CHART_RANGES]
    for joint in JOINT_NAMES:
        fitted = [v.joints[joint] for v in views if joint in v.joints and v.joints[joint].ok]
        if not fitted:
            continue
        def cat(name: str, fitted: list = fitted) -> np.ndarray:
            return np.concatenate([getattr(j, name) for j in fitted])

        ranges[0][joint] = padded_range(np.degrees(cat("angle_rad")))
        ranges[1][joint] = padded_range(np.concatenate([cat("moment_nm"), cat("moment_fit_nm"), cat("moment_constant_nm")]),
                                        include_zero=True)
        ranges[2][joint] = padded_range(cat("stiffness_nm_per_rad"), include_zero=True)
    return joint_charts(*ranges)


def body_bounds(markers_xz: np.ndarray | None) -> tuple[float, float, float, float]:
    """Lab x-z region (m) holding every marker position, plus a margin, for the body view."""
    if markers_xz is None or not np.isfinite(markers_xz).any():
        return (-0.8, 0.8, -0.1, 1.9)
    x, z = markers_xz[..., 0], markers_xz[..., 1]
    cx = 0.5 * (np.nanmin(x) + np.nanmax(x))
    z1 = float(np.nanmax(z)) + 0.15
    half = max(0.5 * (z1 + 0.1) * 0.75, 0.5 * (np.nanmax(x) - np.nanmin(x)) + 0.3)
    return (float(cx - half), float(cx + half), -0.1, z1)


def log_session(rec: rr.RecordingStream, recording: Recording, analysis, fits: list[dict] | None) -> SessionSummary:
    """Log a whole analysed recording to ``rec``: body, signals, per-stance views and trends.

    Parameters
    ----------
    rec : rerun.RecordingStream
    recording : Recording
        The raw recording (force plate, markers, subject).
    analysis : hop_impedance.biomech.analysis.RecordingAnalysis
        Its analysis (``analysis.start_ns`` is the zero of the ``time`` timeline).
    fits : list of dict or None
        One ``{joint: JointImpedanceFit}`` per stance (``fit_recording``), or
        None to draw the inverse dynamics without fits.

    Returns
    -------
    SessionSummary
    """
    t0 = analysis.start_ns
    log_static_styles(rec)
    markers_xz = None
    if recording.markers is not None and len(recording.markers):
        markers_xz = sagittal_markers(recording.markers)
        log_body(rec, (recording.markers.stamp_ns - t0) * 1e-9, markers_xz)
    force = recording.force
    log_ground_reaction(
        rec,
        (force.stamp_ns - t0) * 1e-9,
        force.force_n[:, [0, 2]],
        cop_x_from_wrench(force.force_n, force.torque_nm),
        analysis.subject.body_weight_n,
    )
    views = stance_views(analysis, fits)
    charts = charts_for(views)
    log_chart_frames(rec, charts)
    for stance, view in zip(analysis.stances, views):
        log_stance_interval(rec, stance.touchdown_s, stance.takeoff_s)
        if stance.joints is not None:
            js = stance.joints
            log_joint_series(rec, stance.touchdown_s + js.time_s, js.angle_rad, js.angular_velocity_rad_s, js.moment_nm,
                             js.power_w)
        log_stance(rec, view, charts)
    rejected = {v.index: v.rejection_reason for v in views if v.rejection_reason}
    fitted = sum(1 for v in views if not v.rejection_reason and any(j.ok for j in v.joints.values()))
    return SessionSummary(len(views), fitted, rejected, 0 if markers_xz is None else len(markers_xz), len(force))


def new_recording_stream(recording_id: str | None = None) -> rr.RecordingStream:
    """A recording stream for hop_impedance without the wall-clock ``log_time``/``log_tick`` timelines."""
    rec = rr.RecordingStream(APPLICATION_ID, recording_id=recording_id)
    rec.set_log_time_enabled(False)
    rec.set_log_tick_enabled(False)
    return rec


def analyze_and_fit(recording: Recording):
    """Batch analysis and impedance fits of a recording: ``(analysis, fits)``."""
    from hop_impedance.biomech.analysis import analyze_recording
    from hop_impedance.impedance.recording_fits import fit_recording

    analysis = analyze_recording(recording)
    return analysis, fit_recording(analysis)


DEFAULT_VIEWER_URL = "rerun+http://127.0.0.1:9876/proxy"


def open_sinks(
    rec: rr.RecordingStream,
    blueprint,
    save: str | Path | None = None,
    connect_url: str | None = None,
    spawn: bool = False,
    port: int = 9876,
) -> None:
    """Send ``rec`` to an .rrd file, a running viewer and/or a freshly spawned viewer.

    Parameters
    ----------
    rec : rerun.RecordingStream
    blueprint : rerun.blueprint.Blueprint
        Sent as the default blueprint to every sink.
    save : path, optional
        .rrd file to write (parent folders are created).
    connect_url : str, optional
        gRPC address of a running viewer, e.g. :data:`DEFAULT_VIEWER_URL`.
    spawn : bool
        Start a viewer on loopback ``port`` and stream to it (needs a display).
    port : int

    Raises
    ------
    ValueError
        When no sink is asked for.
    """
    sinks: list = []  # rr.GrpcSink and rr.FileSink
    if spawn:
        ensure_analytics_disabled()
        rr.spawn(port=port, connect=False, hide_welcome_screen=True)
        connect_url = connect_url or f"rerun+http://127.0.0.1:{port}/proxy"
    if connect_url:
        sinks.append(rr.GrpcSink(connect_url))
    if save is not None:
        Path(save).parent.mkdir(parents=True, exist_ok=True)
        sinks.append(rr.FileSink(str(save)))
    if not sinks:
        raise ValueError("no Rerun output: give a file to save, a viewer address to connect to, or spawn a viewer")
    rec.set_sinks(*sinks, default_blueprint=blueprint)


def view_recording(
    recording_path: str | Path,
    save: str | Path | None = None,
    connect_url: str | None = None,
    spawn: bool = False,
    analysis=None,
    fits: list[dict] | None = None,
) -> SessionSummary:
    """Analyse (unless ``analysis`` is given), fit and log a recording to the chosen sinks.

    Parameters
    ----------
    recording_path : str or Path
        Contract MCAP recording.
    save, connect_url, spawn
        Outputs, as in :func:`open_sinks`.
    analysis : RecordingAnalysis, optional
        Its analysis; None runs :func:`analyze_recording` and :func:`fit_recording`.
    fits : list of dict, optional
        One ``{joint: JointImpedanceFit}`` per stance; with ``analysis`` given
        and ``fits`` None the views show the inverse dynamics without fits.

    Returns
    -------
    SessionSummary
    """
    from hop_impedance.io.recording_io import load_recording

    ensure_analytics_disabled()
    recording = load_recording(recording_path)
    if analysis is None:
        analysis, fits = analyze_and_fit(recording)
    rec = new_recording_stream()
    markers = sagittal_markers(recording.markers) if recording.markers is not None and len(recording.markers) else None
    open_sinks(rec, default_blueprint(body_bounds(markers)), save=save, connect_url=connect_url, spawn=spawn)
    summary = log_session(rec, recording, analysis, fits)
    rec.flush()
    rec.disconnect()
    return summary


def write_rrd(recording_path: str | Path, analysis, fits: list[dict] | None, out_path: str | Path) -> SessionSummary:
    """Write the full view of a recording to an .rrd file (with the default blueprint).

    For ``make demo``. Open the file with ``.venv/bin/rerun OUT.rrd``.

    Parameters
    ----------
    recording_path : str or Path
        Contract MCAP recording.
    analysis : RecordingAnalysis or None
        Its analysis; None runs the analysis and the fits.
    fits : list of dict or None
        One ``{joint: JointImpedanceFit}`` per stance (``fit_recording``);
        None with an analysis given draws no fits.
    out_path : str or Path
        The .rrd to write (parent folders are created).

    Returns
    -------
    SessionSummary
    """
    return view_recording(recording_path, save=out_path, analysis=analysis, fits=fits)
