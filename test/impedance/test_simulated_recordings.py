"""Recovery on the simulator's recordings (recordings/*.truth.json), once they exist.

Uses the truth file's noise-free joint samples of every stance (written by
``hop_impedance.simulation.truth``: ``stances[i].samples.t_s / rho_rad /
omega_rad_s / moments_nm`` and ``stances[i].impedance[joint]`` with the Eq. 3
coefficients). The simulator integrates the law as ODE states, independently
of :mod:`hop_impedance.impedance.regression_model`, so agreement is a real
check. Only k0..b3 are compared: the touchdown intercept m0 depends on how the
touchdown moment is split (see docs/impedance_model.md) and the column space
is the same for any split.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from hop_impedance.impedance.regression_model import TERM_NAMES
from hop_impedance.impedance.stance_fit import FitOptions, fit_joint_stance

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"
TRUTH_FILES = sorted(RECORDINGS.glob("*.truth.json"))


def pure_law_stances(truth: dict):
    """Stances whose moment is only the Eq. 3 law (no activation or push-off term)."""
    for stance in truth.get("stances", []):
        if stance.get("activation") or stance.get("push_off"):
            continue
        yield stance


@pytest.mark.skipif(not TRUTH_FILES, reason="no simulator recordings (recordings/*.truth.json) yet")
@pytest.mark.parametrize("truth_path", TRUTH_FILES, ids=lambda p: p.name)
def test_truth_samples_recover_the_simulated_coefficients(truth_path):
    truth = json.loads(truth_path.read_text())
    checked = 0
    for stance in pure_law_stances(truth):
        s = stance["samples"]
        t = np.asarray(s["t_s"], float)
        rho = np.asarray(s["rho_rad"], float)
        omega = np.asarray(s["omega_rad_s"], float)
        moments = np.asarray(s["moments_nm"], float)
        for j, joint in enumerate(("ankle", "knee", "hip")):
            true = stance["impedance"][joint]
            terms = tuple(name for name in TERM_NAMES if true.get(name, 0.0) != 0.0)
            if not {"k0", "k1"} <= set(terms):
                continue
            fit = fit_joint_stance(t - t[0], rho[:, j], omega[:, j], moments[:, j], FitOptions(reduce=False, terms=terms))
            assert fit.ok, fit.rejection_reason
            for name in ("k0", "k1"):
                assert fit.coefficients[name] == pytest.approx(true[name], rel=0.02), (joint, name)
            checked += 1
    if checked == 0:
        pytest.skip(f"{truth_path.name}: no stance driven by the pure Eq. 3 law")
