"""Energy balance per stance: inverse dynamics' net joint work against the plate's own energy figures.

For each complete stance of each recording:

- ``W_joints``: the analysis' net joint work ``int sum_j P_j dt`` (``P_j = -M_j omega_j``; the ID moments come from
  the plate, the joint rates from the markers), as discovery's ``measured_net_joint_work_j`` measures it;
- ``dE_com``: the change of the centre of mass's energy from touchdown to take-off, from the plate alone: Fz minus
  its flight median (offset), divided by the subject's mass, minus g, integrated twice over the whole recording;
  the velocity's constant and a linear drift are chosen so that the centre of mass stands at the same height at
  every touchdown (least squares), as for hopping in place;
- ``W_ground``: the work of the ground on the toe, ``int Fz dz_toe + int Fx dx_toe`` (raw toe marker; zero on a
  rigid plate, negative on a compliant ground that keeps what it absorbs).

For a body whose segments move alike at touchdown and take-off, ``W_joints + W_ground = dE_com``; the last column
is that imbalance. Segment motion about the centre of mass is left out, so an asymmetric stance (a push-off) shows a
few J. A lag between the marker and plate streams shows as a large imbalance: it falsifies the joint work, not the
plate's energy (session 15: the outside ``stream_latency_1701`` -56.7 J, its nulls within +-1.3 J).

Usage: .venv/bin/python bench/discovery_energy_balance.py REC.mcap [REC.mcap ...]
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.integrate import cumulative_trapezoid, trapezoid

from hop_impedance.biomech.analysis import analyze_recording
from hop_impedance.io.recording_io import load_recording

G = 9.81
#: Flight samples this far from the events (s) give the plate's flight baseline.
FLIGHT_MARGIN_S = 0.03


def stance_energies(path: str) -> np.ndarray:
    """Per complete stance ``(W_joints, dE_com, W_ground)`` in J, shape (n, 3); NaN where the stance has no joints."""
    rec = load_recording(path)
    an = analyze_recording(rec)
    assert rec.subject is not None and rec.markers is not None  # analyze_recording raises without a subject
    m = rec.subject.body_mass_kg
    t = (rec.force.stamp_ns - an.start_ns) * 1e-9
    fz, fx = rec.force.force_n[:, 2], rec.force.force_n[:, 0]
    st = [s for s in an.stances if s.complete]
    flight = np.zeros_like(t, bool)
    for a, b in zip(st[:-1], st[1:]):
        flight |= (t > a.takeoff_s + FLIGHT_MARGIN_S) & (t < b.touchdown_s - FLIGHT_MARGIN_S)
    offset = float(np.median(fz[flight])) if flight.any() else 0.0
    v = cumulative_trapezoid((fz - offset) / m - G, t, initial=0.0)
    z = cumulative_trapezoid(v, t, initial=0.0)
    t_td = np.array([s.touchdown_s for s in st])
    c = np.linalg.lstsq(np.c_[np.ones_like(t_td), t_td, t_td**2 / 2], -np.interp(t_td, t, z), rcond=None)[0]
    v, z = v + c[1] + c[2] * t, z + c[1] * t + c[2] * t**2 / 2
    t_m = (rec.markers.stamp_ns - an.start_ns) * 1e-9
    toe = rec.markers.positions_m[:, list(rec.markers.names).index("toe")]
    rows = []
    for s in st:
        v_td, v_to = np.interp([s.touchdown_s, s.takeoff_s], t, v)
        z_td, z_to = np.interp([s.touchdown_s, s.takeoff_s], t, z)
        d_e = 0.5 * m * (v_to**2 - v_td**2) + m * G * (z_to - z_td)
        sel = (t >= s.touchdown_s) & (t <= s.takeoff_s)
        w_ground = (trapezoid(fz[sel] - offset, np.interp(t[sel], t_m, toe[:, 2]))
                    + trapezoid(fx[sel], np.interp(t[sel], t_m, toe[:, 0])))
        w_joints = np.nan
        if s.joints is not None and s.rejection_reason is None:
            w_joints = float(trapezoid(np.asarray(s.joints.power_w).sum(axis=1), np.asarray(s.joints.time_s)))
        rows.append((w_joints, d_e, w_ground))
    return np.array(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("recordings", nargs="+")
    args = ap.parse_args()
    print(f"{'recording':50s} {'n':>2s}  {'W_joints (ID)':>15s}  {'dE_com (plate)':>15s}  {'W_ground':>14s}  "
          f"{'W_joints + W_ground - dE_com':>28s}   (J per stance, mean (SD))")
    for path in args.recordings:
        r = stance_energies(path)
        imb = r[:, 0] + r[:, 2] - r[:, 1]

        def cell(x: np.ndarray, width: int) -> str:
            return f"{np.nanmean(x):+7.2f} ({np.nanstd(x):4.2f})".rjust(width)

        print(f"{path.rsplit('/', 1)[-1][:50]:50s} {len(r):2d}  {cell(r[:, 0], 15)}  {cell(r[:, 1], 15)}  "
              f"{cell(r[:, 2], 14)}  {cell(imb, 28)}")


if __name__ == "__main__":
    main()
