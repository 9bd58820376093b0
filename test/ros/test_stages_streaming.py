"""The streaming stages the nodes wrap: the detector's pending stance is public and equals the next finished one."""

import numpy as np

from hop_impedance.biomech.stance_detection import DetectorOptions, StanceDetector


def _hops(n_hops: int = 3, fs: float = 1000.0, contact_s: float = 0.25, flight_s: float = 0.2, peak_n: float = 2000.0):
    """Half-sine contact forces separated by flights of zero force (true events known)."""
    period = contact_s + flight_s
    t = np.arange(int((n_hops * period + flight_s) * fs)) / fs
    phase = (t - flight_s) % period
    in_contact = (t >= flight_s) & (phase < contact_s)
    fz = np.where(in_contact, peak_n * np.sin(np.pi * phase / contact_s), 0.0)
    touchdowns = flight_s + period * np.arange(n_hops)
    return t, fz, touchdowns, touchdowns + contact_s


def test_pending_stance_is_the_confirmed_takeoff_until_the_next_touchdown():
    t, fz, td, to = _hops()
    det = StanceDetector(DetectorOptions())
    assert det.pending_stance is None
    # through the first take-off plus min_flight_s: confirmed, not yet in stances
    upto = np.searchsorted(t, to[0] + 0.06)
    det.push(t[:upto], fz[:upto])
    pending = det.pending_stance
    assert pending is not None and det.stances == []
    assert abs(pending.touchdown_s - td[0]) < 0.003 and abs(pending.takeoff_s - to[0]) < 0.003
    assert np.isnan(pending.baseline_after_n)
    # at the next touchdown it moves to stances with the flight baseline (0 N here) filled in
    upto2 = np.searchsorted(t, td[1] + 0.01)
    det.push(t[upto:upto2], fz[upto:upto2])
    assert len(det.stances) == 1 and det.stances[0].takeoff_s == pending.takeoff_s
    assert det.stances[0].baseline_after_n == 0.0
    assert det.pending_stance is None
