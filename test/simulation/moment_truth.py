"""Analysed joint moments against a simulated recording's true ones (the simulator round-trip tests)."""

from __future__ import annotations

import numpy as np


def analysed_and_true_moments(rec, truth) -> list[tuple[np.ndarray, np.ndarray]]:
    """``analyze`` a noise-free recording (20 Hz cut-off) and pair each stance's moments with the truth's.

    Asserts one accepted stance per true stance. Returns per stance ``(estimated, true)``, both (n, 3) N m at
    the truth's sample times; estimated is NaN where the analysed stance does not cover a truth sample.
    """
    from hop_impedance.biomech import analysis

    result = analysis.analyze_recording(rec, analysis.AnalysisOptions(marker_cutoff_hz=20.0, force_cutoff_hz=20.0))
    good = [s for s in result.stances if s.rejection_reason is None]
    assert len(good) == len(truth["stances"])
    pairs = []
    for s, ts in zip(good, truth["stances"]):
        tt = np.array(ts["samples"]["t_s"])
        est = np.stack([np.interp(tt, s.touchdown_s + s.joints.time_s, s.joints.moment_nm[:, j],
                                  left=np.nan, right=np.nan) for j in range(3)], 1)
        pairs.append((est, np.array(ts["samples"]["moments_nm"])))
    return pairs
