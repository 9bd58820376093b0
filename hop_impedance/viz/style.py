"""Entity paths, colours and display scales shared by the offline view and the live bridge.

Entity tree (mirrors what is on screen)::

    body/segments, body/markers, body/grf, body/ground     sagittal stick figure (2D, m)
    signals/grf/vertical_bw, signals/grf/in_stance          vertical GRF (BW), 0/1 stance marker
    signals/angle_deg/<joint>                               rho (deg, flexion positive)
    signals/velocity_deg_s/<joint>                          d(rho)/dt (deg/s)
    signals/moment_nm/<joint>/inverse_dynamics              net moment (N m, extensor positive)
    signals/moment_nm/<joint>/variable_fit                  seed model fit (N m)
    signals/power_w/<joint>                                 -M d(rho)/dt (W)
    stiffness/<joint>                                       K(t) of each stance (N m/rad)
    charts/<joint>/...                                      moment-angle loop and K(rho) charts
    trend/k0/<joint>, trend/k1/<joint>                      per-stance coefficients
    stances/table, stances/log                              fit table (markdown), event log

Display choice: angles and angular velocities are shown in degrees (what
people read); every other quantity keeps its SI unit, named in the path.
"""

from __future__ import annotations

from hop_impedance.biomech.joint_angles import JOINT_NAMES

TIMELINE = "time"  #: duration timeline: s since the recording's first message
STANCE_TIMELINE = "stance"  #: sequence timeline: stance index (trend views)

BODY = "body"
SEGMENTS = "body/segments"
MARKERS = "body/markers"
GRF_ARROW = "body/grf"
GROUND = "body/ground"
GRF_BW = "signals/grf/vertical_bw"
IN_STANCE = "signals/grf/in_stance"
ANGLE = "signals/angle_deg"
VELOCITY = "signals/velocity_deg_s"
MOMENT = "signals/moment_nm"
POWER = "signals/power_w"
STIFFNESS = "stiffness"
CHARTS = "charts"
TREND = "trend"
TABLE = "stances/table"
EVENT_LOG = "stances/log"

#: One colour per joint (ankle, knee, hip), RGB.
JOINT_COLORS: dict[str, tuple[int, int, int]] = {
    "ankle": (31, 119, 180),
    "knee": (255, 127, 14),
    "hip": (44, 160, 44),
}
FIT_COLOR = (235, 235, 235)  # light: the viewer's theme is dark
CONSTANT_COLOR = (230, 60, 60)
HISTORY_COLOR = (110, 110, 110)
GRF_COLOR = (214, 39, 40)
SEGMENT_COLOR = (150, 110, 220)
MARKER_COLOR = (240, 240, 240)

#: GRF arrow length per body weight (m/BW): 3 BW is drawn 1.2 m long next to a 1.6 m body.
GRF_ARROW_M_PER_BW = 0.4
#: Below this vertical force (N) there is no centre of pressure and no arrow.
MIN_COP_FORCE_N = 20.0


def moment_path(joint: str, kind: str) -> str:
    """``signals/moment_nm/<joint>/<kind>``, kind ``inverse_dynamics`` or ``variable_fit``."""
    return f"{MOMENT}/{joint}/{kind}"


def chart_path(joint: str, *parts: str) -> str:
    """``charts/<joint>/<parts...>``."""
    return "/".join((CHARTS, joint) + parts)


__all__ = [name for name in dir() if name.isupper()] + ["JOINT_NAMES", "moment_path", "chart_path"]
