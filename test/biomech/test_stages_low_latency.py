"""Low-latency streaming (window ends ``post_pad_s`` after take-off) against the batch analysis.

The low-latency stage sees each stance's window end 50 ms after take-off
instead of at the next touchdown, so the zero-lag filters and splines see a
different edge and the flight baseline is shorter (stages.py docstring). The
difference must stay small where it matters to a controller: the fitted
coefficients. The bound is 5 % on k0 and 2 % on k1 (measured with the
short-window treatment of analysis.extend_past_window: k0 0.88 %, k1 0.81 %;
session 33's recording: k0 0.73 %, k1 1.12 % over the 28 fits with the batch's
terms; before it, with the filters' own edge padding: k0 3.0 %, k1 1.1 %): far
inside the stance-to-stance spread of the fits on noisy data. Figures quoted in docs/pipeline.md are printed by
``.venv/bin/python -m pytest test/biomech/test_stages_low_latency.py -s -q``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from biomech_synth import push_in_chunks

from hop_impedance.biomech.analysis import analyze_recording, recording_span
from hop_impedance.biomech.stages import StanceAnalysisStage
from hop_impedance.impedance.recording_fits import default_fit_options, fit_stance_joints
from hop_impedance.io.recording_io import load_recording

RECORDING = Path(__file__).resolve().parents[2] / "recordings" / "sim_2p20hz_hard.mcap"
JOINTS = ("ankle", "knee", "hip")
POST_PAD_S = 0.05


def _stream(stage: StanceAnalysisStage, data, chunk_s: float = 0.02) -> list:
    """Push ``data`` (a SpanData) through ``stage`` in chunks of ``chunk_s`` and flush."""
    edges = np.arange(data.force_t_s[0], data.force_t_s[-1] + chunk_s, chunk_s)
    out = [stance for _, emitted in push_in_chunks(stage, data, edges) for stance in emitted]
    return out + stage.flush()


@pytest.mark.skipif(not RECORDING.exists(), reason="bundled recording missing")
def test_low_latency_coefficients_stay_close_to_batch():
    rec = load_recording(RECORDING)
    batch = analyze_recording(rec)
    stage = StanceAnalysisStage(batch.model, rec.subject.body_mass_kg, batch.options, post_pad_s=POST_PAD_S)
    live = _stream(stage, recording_span(rec))
    assert [(s.touchdown_s, s.takeoff_s) for s in live] == [(s.touchdown_s, s.takeoff_s) for s in batch.stances]
    options = default_fit_options(batch.options)
    worst = {name: 0.0 for name in ("k0", "k1")}
    compared = 0
    other_terms = []
    for b, s in zip(batch.stances, live):
        if b.rejection_reason is not None:
            assert s.rejection_reason is not None
            continue
        fb, fs = fit_stance_joints(b, options), fit_stance_joints(s, options)
        for joint in JOINTS:
            if not (fb[joint].ok and fs[joint].ok):
                continue
            if fb[joint].terms != fs[joint].terms:
                other_terms.append((b.index, joint))
                continue
            for name in worst:
                if name in fb[joint].coefficients:
                    ref = fb[joint].coefficients[name]
                    rel = abs(fs[joint].coefficients[name] - ref) / abs(ref)
                    worst[name] = max(worst[name], rel)
            compared += 1
    print(f"\nlow-latency vs batch on {RECORDING.name}: {compared} joint fits, "
          f"max relative difference k0 {worst['k0']:.2%}, k1 {worst['k1']:.2%}")
    # the model reduction of two knees (session 33's recording, the trunk-still flight) ends on other terms, at the
    # edge of its tests: stance 4's batch keeps k3 (p 0.013) and drops b0 (p 0.32), the live window drops k3 as
    # collinear and keeps b0 (p 0.054); stance 5's batch drops b0 at p 0.0511 (alpha 0.05), the live window keeps it.
    # The d8eda79 recording: none. Any other stance or joint is a change to look at.
    assert other_terms == [(4, "knee"), (5, "knee")]
    assert compared >= 20
    assert worst["k0"] < 0.05 and worst["k1"] < 0.02
