"""Per-leg k0/k1 recovery on a simulated asymmetric bilateral recording (issue 21, "must be shown").

Construction and limits: :mod:`hop_impedance.validation.bilateral_recovery`
(left leg = a seed Table 2 trial at 2.20 Hz, right leg = one at 1.87 Hz, each
plate half its trial's ground wrench; each leg's truth = half its trial's
law). Seeds 11-14, 4 hops, noise-free, analysed at 40 Hz: the lumped
recovery test's trials and settings (test/impedance/test_simulated_recordings.py),
and its rule: each median within the 2 % target, a combination that misses it
marked ``xfail(strict=True)`` with the measured figure (it fails loudly the day
it passes). Same figures: ``.venv/bin/python bench/per_leg_recovery.py``.

Every median is within the target since 2026-11-24 (``bench/per_leg_recovery.py``,
23:00 UTC): left (2.20 Hz) hip k1 +0.75 % [-0.11, +1.66] (lumped +1.15 %), the
largest |median| 0.93 % (right knee k0); over seeds 11-30 (``--seeds $(seq 11 30)
--first-once``) every per-leg median within 0.96 %, left hip k1 +0.74 % [+0.19,
+1.65] (it was +4.37 %), lumped +1.24 % (was +3.54 %). It was the one miss, +2.31 % (lumped
+1.79 %), until the wrench was put through the markers' own sampling, filter
and spline (:func:`hop_impedance.biomech.kinematics.wrench_through_marker_chain`;
per leg the rigid-fit markers' chain: sampled at the rate the markers were
measured at, ``AnalysisOptions.marker_measured_rate_hz``, splined onto the
1 kHz grid and filtered there; docs/impedance_model.md, "Stance edges"). What
was measured before that change (bootstrap intervals and paired per-stance
per-leg - lumped differences):

- Not the construction: with the leg's markers as measured (``--measured``)
  each leg's moments are half the lumped ones to 0.000 % of peak (segment
  halving and "half its law" are exact); the per-leg stance then ends 1.1-2.0 ms
  earlier (seed 11) (the detector's levels are fractions of the whole body weight, the
  plate carries half), which alone moves one stance's hip k1 by up to a few
  points (paired SD 2.1 points left, 1.2 right).
- Not the 200 Hz pass-through: at 450 Hz no figure moves by more than 0.02.
- The rigid-fit kinematics (spline to 1 kHz, then 40 Hz) shift the hip k1:
  paired per-leg - lumped median +0.95 [+0.43, +3.23] points left and +3.37
  [+1.62, +4.04] right on these seeds; over seeds 11-30 (each trial's first
  stance, the same hop in every seed, counted once: ``--seeds $(seq 11 30)
  --first-once``) +0.35 [-0.32, +2.10] left (sampling) and +2.37 [+1.92,
  +3.05] right (systematic). Their hip moments are the closer to the
  simulator's truth (seed 11, RMS 0.9-3.1 % of its peak against 4.7-6.0 %).
- Over seeds 11-30 the 2.20 Hz hip k1 misses 2 % per leg (+4.37 %) and
  lumped (+3.54 %) alike, and the right per-leg hip k1 too (+2.73 %, lumped
  +0.05 %): the 4-seed passes of those are draws of seeds 11-14, not margins.
- Where: the stance edges. Leaving 20 ms at each edge out of both analyses'
  fits (``--seeds $(seq 11 30) --first-once --edge 0.02``) puts every per-leg
  median within 0.62 % (hip k1 -0.27 % [-0.41, +0.03] left, -0.03 % [-0.23,
  +0.20] right; lumped -0.74 %, +1.38 %): the touchdown and take-off force
  steps that 40 Hz kinematics of 100 Hz markers cannot follow decide the
  noise-free hip k1, the per-leg model does not. The test keeps the product's
  whole-stance fit (as the lumped test does: edges left out were worse with
  noise, docs/impedance_model.md); whether to leave edges out is not this
  test's to choose. The mechanism was the force seeing a sharper step than
  the marker kinematics (see above), now removed in the analysis itself.
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.validation.bilateral_recovery import recover_legs
from hop_impedance.validation.coefficient_recovery import JOINTS, RecoveryResult

SEEDS = (11, 12, 13, 14)
FREQ_HZ = {"left": 2.20, "right": 1.87}
TARGET = 0.02  # the lumped noise-free target (bench/recovery_errors.py, test_simulated_recordings.TOLERANCE)
#: (side, joint, coefficient) -> measured |median error| where the target is missed (bench/per_leg_recovery.py):
#: none since 2026-11-24 (left hip k1 was 0.0231; module docstring).
MISSED_TARGETS: dict[tuple[str, str, str], float] = {}


@pytest.fixture(scope="module")
def pooled():
    out = {(kind, side): RecoveryResult() for kind in ("per_leg", "lumped") for side in FREQ_HZ}
    for seed in SEEDS:
        legs, analyses, _, lumped = recover_legs(FREQ_HZ, seed, n_hops=4, lumped=True)
        assert analyses["left"].stances and analyses["right"].stances
        for side in FREQ_HZ:
            out["per_leg", side].extend(legs[side])
            out["lumped", side].extend(lumped[side])
    return out


@pytest.mark.slow
@pytest.mark.parametrize("coefficient", ["k0", "k1"])
@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("joint", JOINTS)
def test_each_leg_recovers_its_own_law(pooled, side, joint, coefficient, request):
    """Measured median k0 / k1 errors (%), default per-leg analysis (rigid-segment fit): left (2.20 Hz law)
    ankle +0.65/-0.17, knee +0.67/-0.85, hip -0.27/+0.75; right (1.87 Hz law) ankle +0.75/-0.20, knee
    +0.93/-0.48, hip +0.02/-0.38. All within 2 % (module docstring)."""
    missed = MISSED_TARGETS.get((side, joint, coefficient))
    if missed is not None:
        request.applymarker(pytest.mark.xfail(strict=True, reason=f"measured about {missed:.2%} (target {TARGET:.0%})"))
    errors = pooled["per_leg", side].error_array(joint)
    lumped = pooled["lumped", side].error_array(joint)
    assert errors.shape[0] >= 3 * len(SEEDS) and errors.shape[0] == lumped.shape[0]
    c = ("k0", "k1").index(coefficient)
    median, lumped_median = np.median(errors[:, c]), np.median(lumped[:, c])
    print(f"{side} {joint} {coefficient}: per-leg median {100 * median:+.2f} %, lumped {100 * lumped_median:+.2f} %")
    assert abs(median) < TARGET


@pytest.mark.slow
def test_the_legs_differ_as_their_laws_do(pooled):
    """The asymmetry is recovered: each leg's fitted k0/k1 are half of its own trial's law, and the two
    trials' laws differ (2.20 Hz: knee k1 884.8; 1.87 Hz: 541.3 N m/rad), so a fit that mixed the legs
    would be off by tens of percent on at least one side."""
    from hop_impedance.simulation.scenarios import SEED_TABLE2

    ratio = SEED_TABLE2[2.20]["k1"][1] / SEED_TABLE2[1.87]["k1"][1]
    assert ratio > 1.5
    for side in FREQ_HZ:
        assert np.all(np.abs(pooled["per_leg", side].error_array("knee")) < 0.05)
