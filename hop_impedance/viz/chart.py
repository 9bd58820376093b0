"""Small x-y charts drawn in a Rerun 2D view (moment-angle loops, K(rho)).

Rerun's time-series views always plot against a timeline, so curves against
an angle (a moment-angle loop goes forth and back in rho) are drawn as line
strips in a ``Spatial2DView``. A :class:`Chart` maps data units into a box of
view units; axes, ticks and titles are logged once (static) next to it.
Rerun's 2D views draw y downwards, so the mapping flips y.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import rerun as rr
from matplotlib.ticker import MaxNLocator

AXIS_COLOR = (90, 90, 90)


@dataclass(frozen=True)
class Chart:
    """A box of ``width`` x ``height`` view units at ``(left, top)`` showing data ranges.

    Attributes
    ----------
    x_range, y_range : tuple of float
        Data shown at the box's left/right and bottom/top edges.
    x_title, y_title : str
        Axis titles with units.
    left, top, width, height : float
        Box placement in view units (y grows downwards in the view).
    """

    x_range: tuple[float, float]
    y_range: tuple[float, float]
    x_title: str
    y_title: str
    left: float = 0.0
    top: float = 0.0
    width: float = 100.0
    height: float = 70.0

    def to_view(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Data points -> view points, shape (n, 2); y is flipped (up in the data = up on screen)."""
        (x0, x1), (y0, y1) = self.x_range, self.y_range
        u = self.left + (np.asarray(x, float) - x0) / (x1 - x0) * self.width
        v = self.top + self.height - (np.asarray(y, float) - y0) / (y1 - y0) * self.height
        return np.column_stack([u, v])


def padded_range(values: np.ndarray, pad: float = 0.08, include_zero: bool = False) -> tuple[float, float]:
    """Finite min/max of ``values`` widened by ``pad`` of the span on each side (never empty)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if include_zero:
        v = np.append(v, 0.0)
    if v.size == 0:
        return (0.0, 1.0)
    lo, hi = float(v.min()), float(v.max())
    span = hi - lo if hi > lo else max(abs(hi), 1.0)
    return (lo - pad * span, hi + pad * span)


def _ticks(lo: float, hi: float) -> np.ndarray:
    ticks = np.asarray(MaxNLocator(nbins=4).tick_values(lo, hi), float)
    return ticks[(ticks >= lo) & (ticks <= hi)]


def log_chart_frame(rec: rr.RecordingStream, path: str, chart: Chart, title: str) -> None:
    """Log the chart's box, zero line, tick labels and titles under ``path`` (static).

    Parameters
    ----------
    rec : rerun.RecordingStream
    path : str
        Entity path of the frame (e.g. ``charts/ankle/loop/frame``).
    chart : Chart
    title : str
        Shown above the box.
    """
    x0, t, w, h = chart.left, chart.top, chart.width, chart.height
    box = [[x0, t], [x0 + w, t], [x0 + w, t + h], [x0, t + h], [x0, t]]
    strips = [box]
    (y0, y1) = chart.y_range
    if y0 < 0.0 < y1:
        z = chart.to_view(np.array(chart.x_range), np.zeros(2))
        strips.append(z.tolist())
    rec.log(f"{path}/axes", rr.LineStrips2D(strips, colors=AXIS_COLOR, radii=-0.5, draw_order=1.0), static=True)
    xt, yt = _ticks(*chart.x_range), _ticks(*chart.y_range)
    x_pts = chart.to_view(xt, np.full(xt.shape, y0)) + [0.0, 4.0]
    y_pts = chart.to_view(np.full(yt.shape, chart.x_range[0]), yt) - [6.0, 0.0]
    labels = [f"{v:g}" for v in xt] + [f"{v:g}" for v in yt]
    title_pts = [[x0 + w / 2, t + h + 10.0], [x0 - 4.0, t - 6.0], [x0 + w / 2, t - 16.0]]
    rec.log(
        f"{path}/labels",
        rr.Points2D(
            np.vstack([x_pts, y_pts, title_pts]),
            labels=labels + [chart.x_title, chart.y_title, title],
            radii=-0.01,
            colors=AXIS_COLOR,
            show_labels=True,
        ),
        static=True,
    )
