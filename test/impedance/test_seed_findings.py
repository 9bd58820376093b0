"""The demo's comparison with the seed (impedance/seed_findings.py) on the bundled 2.2 Hz recording:
Table 2's published k0/k1 as the reference, the recording's own fits as the medians, the per-stance
F-tests' k1 count, and the Fig. 7 line against scipy's linregress (an independent implementation)."""

from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from hop_impedance.biomech.analysis import analyze_recording
from hop_impedance.impedance.recording_fits import fit_recording_trial
from hop_impedance.impedance.seed_findings import JointStance, fig7_line, seed_findings
from hop_impedance.io.recording_io import load_recording

RECORDING = Path(__file__).resolve().parents[2] / "recordings" / "sim_2p20hz_hard.mcap"


@pytest.fixture(scope="module")
def trial():
    rec = load_recording(RECORDING)
    return rec, fit_recording_trial(analyze_recording(rec))


def _stances(trial_fits) -> dict[str, list[JointStance]]:
    out: dict[str, list[JointStance]] = {}
    for fits, own in zip(trial_fits.fits, trial_fits.stance_fits):
        for joint, fit in fits.items():
            if fit.ok:
                out.setdefault(joint, []).append(JointStance(
                    fit.coefficients.get("k0", 0.0), fit.coefficients.get("k1", 0.0), "k1" in own[joint].terms,
                    fit.sse_variable, fit.sse_constant, fit.initial_stiffness, fit.max_stiffness))
    return out


def test_lines_carry_the_seeds_table_2_and_the_recordings_medians(trial):
    rec, trial_fits = trial
    stances = _stances(trial_fits)
    lines = seed_findings(stances, 2.2, rec.subject.body_mass_kg)
    assert rec.subject.body_mass_kg == pytest.approx(54.8)  # the seed's mean subject: no scaling
    ankle, knee, hip = lines[1:4]
    # seed 000, Table 2 at 2.20 Hz (Eq. 10 k0, k1): ankle 301 / 948, knee 231 / 885, hip 175 / 895 (published)
    for line, (k0, k1) in zip((ankle, knee, hip), ((301, 948), (231, 885), (175, 895))):
        assert f"vs {k0:4d}" in line and f"vs {k1:4d}" in line, line
    k0_median = np.median([s.k0 for s in stances["ankle"]])
    assert f"k0 {k0_median:6.0f}" in ankle
    kept = sum("k1" in own["knee"].terms for own, fits in zip(trial_fits.stance_fits, trial_fits.fits) if fits["knee"].ok)
    assert f"own F-test in {kept}/{len(stances['knee'])}" in knee
    below = sum(s.sse_variable < s.sse_constant for s in stances["hip"])
    assert f"below constant in {below}/{len(stances['hip'])}" in hip


def test_fig7_line_matches_scipy(trial):
    _, trial_fits = trial
    points = [(s.initial_stiffness, s.max_stiffness) for rows in _stances(trial_fits).values() for s in rows]
    slope, intercept, r2 = fig7_line(points)
    ref = stats.linregress(*np.asarray(points).T)
    assert (slope, intercept, r2) == pytest.approx((ref.slope, ref.intercept, ref.rvalue**2), rel=1e-9)
    assert len(points) == 30 and np.isnan(fig7_line(points[:2])[2])
