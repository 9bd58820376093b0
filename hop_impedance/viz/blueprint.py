"""The default layout shown on first open (stored in the .rrd / sent to a live viewer).

Three columns: the body (stick figure with GRF arrow over the fit table and
event log); the time series (GRF with stance marks, angles, velocities,
moments with fits, powers, K(t)); the per-stance charts (one view per joint
with its moment-angle loop and K(rho)) over the k0/k1 trends.
"""

from __future__ import annotations

import rerun.blueprint as rrb

from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.viz import style as S


def _series(origin: str, name: str) -> rrb.TimeSeriesView:
    return rrb.TimeSeriesView(origin=origin, name=name, plot_legend=rrb.PlotLegend(corner="RightTop", visible=True))


def default_blueprint(body_bounds_m: tuple[float, float, float, float] = (-0.8, 0.8, -0.1, 1.9)) -> rrb.Blueprint:
    """Blueprint of every view.

    Parameters
    ----------
    body_bounds_m : tuple
        ``(x_min, x_max, z_min, z_max)`` of the lab x-z region shown around the body (m).

    Returns
    -------
    rerun.blueprint.Blueprint
    """
    x0, x1, z0, z1 = body_bounds_m
    body = rrb.Spatial2DView(
        origin=S.BODY,
        name="Stick figure and GRF",
        visual_bounds=rrb.VisualBounds2D(x_range=[x0, x1], y_range=[-z1, -z0]),
    )
    left = rrb.Vertical(
        body,
        rrb.TextDocumentView(origin=S.TABLE, name="Stance fit"),
        rrb.TextLogView(origin=S.EVENT_LOG, name="Stances"),
        row_shares=[5, 4, 2],
    )
    middle = rrb.Vertical(
        _series("signals/grf", "Vertical GRF (BW), stance marks"),
        _series(S.ANGLE, "Joint angle rho (deg, flexion +)"),
        _series(S.VELOCITY, "Angular velocity (deg/s)"),
        _series(S.MOMENT, "Moment: inverse dynamics and fit (N m, extensor +)"),
        _series(S.POWER, "Joint power (W, absorbed -)"),
        _series(S.STIFFNESS, "K(t) per stance (N m/rad)"),
    )
    charts = [
        rrb.Spatial2DView(
            origin=f"{S.CHARTS}/{joint}",
            name=f"{joint}: moment-angle loop (fit white, constant K red) and K(rho)",
            visual_bounds=rrb.VisualBounds2D(x_range=[-15.0, 235.0], y_range=[-20.0, 85.0]),
        )
        for joint in JOINT_NAMES
    ]
    trends = [_series(f"{S.TREND}/{c}", f"{c} per stance ({u})") for c, u in (("k0", "N m/rad"), ("k1", "N m/rad²"))]
    right = rrb.Vertical(*charts, *trends)
    return rrb.Blueprint(
        rrb.Horizontal(left, middle, right, column_shares=[3, 4, 4]),
        rrb.TimePanel(timeline=S.TIMELINE, state="collapsed"),
        collapse_panels=True,
    )
