"""Terms that the F-tests keep but the constraints pin at zero leave the reduced model.

The reduction tests terms on the unconstrained (OLS) fit. Energy put in by
the muscles during stance (a push-off, or here an added negative damper
-c omega) makes the OLS damping coefficient significantly *negative*; the
constraint B >= 0 (seed Eq. 7) then holds it at exactly 0 in the final fit.
Removing such a term leaves the constrained fit unchanged (its constrained
partial F is 0, p = 1), so the seed's reduction removes it: a published
model must not list a term whose value is 0 and whose p-value is 1.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from conftest import fit_synthetic

from hop_impedance.impedance.synthetic import synthetic_stance

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"


def stance_with_extra_damper(seed: int, damping_nms_per_rad: float):
    """Ankle, 1.87 Hz, realistic noise, plus the moment of a linear damper c * omega (c < 0 puts energy in)."""
    st = synthetic_stance("ankle", 1.87, np.random.default_rng(seed), realistic_noise=True)
    return replace(st, moment_nm=st.moment_nm + damping_nms_per_rad * st.angular_velocity_rad_s)


@pytest.mark.parametrize("seed", range(8))
def test_damping_pinned_at_zero_is_removed_and_the_fit_is_unchanged(seed):
    st = stance_with_extra_damper(seed, -3.0)
    fit = fit_synthetic(st)
    assert fit.ok
    assert not any(name.startswith("b") for name in fit.terms), fit.terms
    assert fit.reduction.steps[-1].reason == "held at zero by the constraints"
    # The same stance fitted with the surviving terms given: identical coefficients (removal changed nothing).
    given = fit_synthetic(st, reduce=False, terms=fit.terms)
    for name, value in given.coefficients.items():
        assert fit.coefficients[name] == pytest.approx(value, rel=1e-6, abs=1e-6)
    assert fit.sse_variable == pytest.approx(given.sse_variable, rel=1e-9)
    assert all(p < 1.0 for p in fit.p_values.values())


@pytest.mark.parametrize("seed", range(4))
def test_positive_damping_is_kept(seed):
    """A real damper (c = +3 N m s/rad) is significant and feasible: kept, with its value."""
    st = stance_with_extra_damper(seed, 3.0)
    fit = fit_synthetic(st)
    assert fit.ok and "b0" in fit.terms
    assert fit.coefficients["b0"] == pytest.approx(3.0 + st.true_coefficients.get("b0", 0.0), abs=1.0)


@pytest.mark.slow
@pytest.mark.skipif(not (RECORDINGS / "sim_1p53hz_hard.mcap").exists(), reason="bundled recording missing")
def test_no_published_term_is_held_at_zero_on_a_push_off_recording():
    """Bundled 1.53 Hz trial (push-off in stance): before, every ankle fit listed b0 = 0 with p = 1."""
    from hop_impedance.biomech.analysis import analyze_recording
    from hop_impedance.impedance.recording_fits import fit_recording
    from hop_impedance.io.recording_io import load_recording

    fits = fit_recording(analyze_recording(load_recording(RECORDINGS / "sim_1p53hz_hard.mcap")))
    checked = 0
    for stance_fits in fits:
        for fit in stance_fits.values():
            if not fit.ok:
                continue
            for name in fit.terms:
                assert fit.coefficients[name] != 0.0 and fit.p_values[name] < 1.0, (name, fit.coefficients)
            checked += 1
    assert checked >= 27
