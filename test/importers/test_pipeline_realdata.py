"""The analysis pipeline on imported real data (OpenCap drop jump, BMC CMJ force only).

Uses hop_impedance.biomech.analysis and hop_impedance.impedance when they are
importable (other packages of the project); skips with the reason otherwise.
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.importers import import_force_only, import_opensim
from hop_impedance.importers.opensim_import import read_mot

from .conftest import CMJ, OPENCAP

analysis = pytest.importorskip("hop_impedance.biomech.analysis", reason="analysis pipeline not available yet")
TRC = OPENCAP / "Subject4_DJ1_markers_trc.txt"
MOT = OPENCAP / "Subject4_DJ1_grf_mot.txt"
IK = OPENCAP / "Subject4_DJ1_ik_mot.txt"
MASS_KG = 60.0


@pytest.fixture(scope="module")
def landing():
    if not TRC.exists():
        pytest.skip("shared data set opencap_dropjump not present")
    rec = import_opensim(TRC, MOT, "opencap_right", mass_kg=MASS_KG)
    result = analysis.analyze_recording(rec)
    complete = [s for s in result.stances if s.rejection_reason is None]
    assert len(complete) == 1, [s.rejection_reason for s in result.stances]
    return complete[0]


def test_contacts(landing):
    # SOURCE.txt: first contact 1.42-2.17 s (force edges at 100 Hz).
    assert landing.touchdown_s == pytest.approx(1.42, abs=0.015)
    assert landing.takeoff_s == pytest.approx(2.17, abs=0.015)


def test_knee_and_hip_angles_follow_opensim_ik(landing):
    """Our rho (contract markers, contract frame) against OpenSim's IK of the same trial."""
    ik = read_mot(IK)  # radians (inDegrees=no)
    t = landing.joints.time_s + landing.touchdown_s
    ours = landing.joints.angle_rad
    knee_ik = np.interp(t, ik.column("time"), ik.column("knee_angle_r"))
    ok = np.isfinite(ours[:, 1])
    assert np.corrcoef(knee_ik[ok], ours[ok, 1])[0, 1] > 0.99
    # knee flexion = rho2 - pi; the marker line differs from the model's by a few degrees
    assert np.degrees(np.mean(ours[ok, 1] - np.pi - knee_ik[ok])) == pytest.approx(0, abs=6)
    hip_ik = np.interp(t, ik.column("time"), ik.column("hip_flexion_r"))
    assert np.corrcoef(hip_ik[ok], ours[ok, 2])[0, 1] > 0.97  # our HAT includes the trunk's lean


def test_moments_plausible_for_a_drop_jump(landing):
    """Peak extensor moments, both legs lumped, per kg.

    Reference: drop-jump landings give per-leg peak knee and ankle extensor
    moments of roughly 1-4 N m/kg (e.g. Bobbert, Huijing & van Ingen Schenau
    1987, Med Sci Sports Exerc 19:332-338: lower in long-contact
    "countermovement" drop jumps like this 0.75 s contact, higher in
    short-contact "bounce" jumps). Both legs together: 2-8 N m/kg.
    """
    m = landing.joints.moment_nm / MASS_KG
    peak, trough = np.nanmax(m, axis=0), np.nanmin(m, axis=0)
    assert np.all((peak > 1.5) & (peak < 8.0)), peak  # ankle, knee, hip
    assert np.all(peak > 2.5 * np.abs(np.minimum(trough, 0))), (peak, trough)  # extensor dominated
    # knee peaks early (absorbing the landing), ankle later (push-off)
    t_peak = landing.joints.time_s[np.nanargmax(m, axis=0)]
    assert t_peak[1] < t_peak[0]


def test_impedance_profiles_for_the_landing(landing):
    """The fits ``hop-impedance analyze`` publishes for this stance (recording_fits.fit_stance_joints).

    Measured (docs/importing.md): ankle k0 + k1 kept, R^2 0.30; knee R^2 0.67; hip R^2 0.84.
    The seed's hopping model describes the knee and hip of this long drop-jump
    contact; at the ankle it keeps a spring that explains under half the moment.
    """
    recording_fits = pytest.importorskip("hop_impedance.impedance.recording_fits", reason="impedance fits not available yet")
    fits = recording_fits.fit_stance_joints(landing)
    for fit in fits.values():
        assert fit.status == "solved" and fit.rejection_reason is None
        assert any(t.startswith("k") for t in fit.terms), fit.terms  # a spring, not an intercept
        assert np.nanmin(fit.stiffness) > -1e-9  # N m/rad, held non-negative
    ankle, knee, hip = fits["ankle"], fits["knee"], fits["hip"]
    assert 0.2 < ankle.r_squared < 0.5, ankle.r_squared
    assert knee.r_squared > 0.5 and hip.r_squared > 0.75, (knee.r_squared, hip.r_squared)


@pytest.mark.skipif(not CMJ.exists(), reason="shared data set bmc_cmj_grf not present")
def test_force_only_runs_stances_and_says_what_is_missing():
    rec = import_force_only(CMJ)
    result = analysis.analyze_recording(rec)
    assert [round(s.touchdown_s, 2) for s in result.stances] == [1.31, 5.64]
    assert all(s.joints is None for s in result.stances)
    assert "joint moments" in rec.warnings[0] and "cannot" in rec.warnings[0]
