"""Per-leg coefficient recovery on a simulated asymmetric bilateral recording (issue 21).

The simulator has one lumped leg. A bilateral recording with a known split is
built from two of its trials of the same subject with different seed Table 2
stiffness (e.g. 2.20 Hz for the left leg, 1.53 Hz for the right):

- left plate = ``share`` x the left trial's ground wrench, right plate =
  ``share`` x the right trial's (same stamps; the summed v1 plate is their sum);
- left markers = the left trial's markers, right markers = the right trial's;
- with ``share = 0.5`` each leg of the per-leg model (half the lumped leg
  segments, :func:`hop_impedance.biomech.per_leg.leg_model`) carries exactly
  half of its trial's lumped dynamics: Newton-Euler is linear in the segment
  masses and the ground wrench together. So each leg's true law is its
  trial's law with k0 and k1 (and b0) halved.

Limits of the construction: the two "legs" are not one body. Each follows
its own trial's timing (touchdowns need not coincide), the summed plate is no
real body's ground reaction, the HAT follows the right trial, and a share
other than 0.5 would need a leg model with ``share`` x the lumped masses,
which no person has. It tests what per-leg analysis adds (each leg's own
plate, stances, markers, half-leg segments, fits), not bilateral coordination.
"""

from __future__ import annotations

import numpy as np

from hop_impedance.validation.coefficient_recovery import (
    compare_with_law,
    law_fit_options,
    record_law_trial,
    simulate_law_trial,
)

#: Each leg's share of its trial's ground wrench (see the module docstring for why 0.5).
SHARE = 0.5


def bilateral_from_trials(left, right, seed: int, noisy: bool = False):
    """A :class:`~hop_impedance.bilateral.BilateralRecording` from two simulated trials and their truths.

    Returns ``(bilateral, truths, recordings)``, the last two ``{"left": ..., "right": ...}``
    (``recordings``: each trial's whole lumped recording, cut like the
    bilateral one); both are cut to the shorter trial's samples so that the
    plates share stamps.
    """
    from hop_impedance.bilateral import BilateralRecording, sum_plates
    from hop_impedance.recording import ForcePlateSeries, MarkerSeries, Recording

    recs, truths = {}, {}
    for k, (side, trial) in enumerate((("left", left), ("right", right))):
        recs[side], truths[side] = record_law_trial(trial, noisy, np.random.default_rng([seed, 1, k]))
    nf = min(len(r.force) for r in recs.values())
    nm = min(len(r.markers) for r in recs.values())
    for r in recs.values():
        if (np.any(r.force.stamp_ns[:nf] != recs["left"].force.stamp_ns[:nf])
                or np.any(r.markers.stamp_ns[:nm] != recs["left"].markers.stamp_ns[:nm])):
            raise ValueError("the two trials are not sampled on the same clock")
    plates = {side: ForcePlateSeries(r.force.stamp_ns[:nf].copy(), SHARE * r.force.force_n[:nf], SHARE * r.force.torque_nm[:nf])
              for side, r in recs.items()}
    markers = {side: MarkerSeries(r.markers.stamp_ns[:nm].copy(), r.markers.names, r.markers.positions_m[:nm].copy())
               for side, r in recs.items()}
    v1 = Recording(sum_plates(plates), markers["right"], recs["right"].subject, "simulated two-leg recording")
    whole = {side: Recording(ForcePlateSeries(r.force.stamp_ns[:nf].copy(), r.force.force_n[:nf], r.force.torque_nm[:nf]),
                             markers[side], r.subject, f"simulated {side}-leg trial") for side, r in recs.items()}
    return BilateralRecording(v1, plates, markers["left"]), truths, whole


def recover_legs(freq_hz: dict[str, float], seed: int, *, n_hops: dict[str, int] | int = 4, cutoff_hz: float = 40.0,
                 noisy: bool = False, lumped: bool = False, rigid: bool = True,
                 skip_first: int = 0, edge_s: float = 0.0):
    """Simulate, build, analyse per leg and fit; per leg a :class:`RecoveryResult` against ``SHARE`` x its law.

    ``freq_hz`` maps ``"left"``/``"right"`` to the hop frequency whose seed
    Table 2 law that leg's trial uses; ``n_hops`` per side (or one for both:
    the faster leg needs more hops to last as long, the recording is cut to the
    shorter trial). Returns ``(results, analyses, fits)``, plus with ``lumped``
    the same recovery by the lumped analysis of each leg's whole trial (the
    v1 path on the unsplit recording), ``{side: RecoveryResult}``. ``rigid``: the per-leg kinematics
    (:func:`~hop_impedance.biomech.per_leg.analyze_leg`; False = the leg's markers as measured).
    ``skip_first``: simulated stances not compared at the start of each trial
    (:func:`~hop_impedance.validation.coefficient_recovery.compare_with_law`; the first lands from
    the same lead-in whatever the seed, so it is one hop however many seeds are pooled).
    ``edge_s``: time left out of the fit's objective at each stance edge (``FitOptions.exclude_*``), both analyses.
    """
    from hop_impedance.biomech.analysis import AnalysisOptions
    from hop_impedance.biomech.per_leg import analyze_legs, fit_legs

    hops = n_hops if isinstance(n_hops, dict) else {side: n_hops for side in freq_hz}
    trials = {side: simulate_law_trial(f, seed, hops[side]) for side, f in freq_hz.items()}
    bilateral, truths, trial_recordings = bilateral_from_trials(trials["left"], trials["right"], seed, noisy)
    analyses = analyze_legs(bilateral, AnalysisOptions(marker_cutoff_hz=cutoff_hz, force_cutoff_hz=cutoff_hz), rigid)
    options = law_fit_options(analyses["left"].options, edge_s)
    fits = fit_legs(analyses, options)
    results = {side: compare_with_law(analyses[side], fits[side], truths[side], law_scale=SHARE, skip_first=skip_first)
               for side in ("left", "right")}
    if not lumped:
        return results, analyses, fits
    from hop_impedance.biomech.analysis import analyze_recording
    from hop_impedance.impedance.recording_fits import fit_recording

    lumped_results = {}
    for side in ("left", "right"):
        whole = trial_recordings[side]
        analysis = analyze_recording(whole, AnalysisOptions(marker_cutoff_hz=cutoff_hz, force_cutoff_hz=cutoff_hz))
        lumped_results[side] = compare_with_law(analysis, fit_recording(analysis, options), truths[side],
                                                skip_first=skip_first)
    return results, analyses, fits, lumped_results

