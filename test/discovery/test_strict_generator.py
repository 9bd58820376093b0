"""The second generator (hop_impedance.validation.strict_generator): independent, lossless, time-symmetric.

Checked against physics, not against our simulator: it must import nothing from
``hop_impedance.simulation`` or ``hop_impedance.discovery``; the sympy-derived equations of motion must
conserve the total mechanical energy of a stance (a wrong mass matrix or velocity term would not);
stances are mirror images about mid-stance; the recording passes our analysis with the hops it holds.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from hop_impedance.validation.strict_generator import StrictConfig, strict_recording
from hop_impedance.validation.strict_generator.generator import (
    _stance,
    _stance_state,
    perturbed_body,
    recording_stiffness,
)

PACKAGE = Path(__file__).resolve().parents[2] / "hop_impedance" / "validation" / "strict_generator"
_CACHE: dict = {}


def test_generator_imports_nothing_from_the_simulator_or_the_discovery():
    imported = set()
    for path in PACKAGE.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                imported.add(node.module)
            elif isinstance(node, ast.Import):
                imported.update(a.name for a in node.names)
    assert imported, "no imports parsed"
    bad = {m for m in imported if m.startswith(("hop_impedance.simulation", "hop_impedance.discovery"))}
    assert not bad, bad


def _one_stance():
    if "stance" not in _CACHE:
        rng = np.random.default_rng(3)
        body = perturbed_body(60.0, 1.65, rng)
        _CACHE["stance"] = _stance(body, rng, StrictConfig(), recording_stiffness(rng))
    return _CACHE["stance"]


def test_stance_conserves_mechanical_energy():
    """Kinetic + gravity + ground + joint-spring energy constant through stance (relative change < 1e-6 of the
    ~600 J total; the kinetic energy at touchdown alone is ~40 J)."""
    st = _one_stance()
    model = st["model"]
    t = np.linspace(0.0, 2 * st["half_s"], 41)
    e = np.array([model.energy_j(*_stance_state(st, tt)) for tt in t])
    q_td, qd_td = _stance_state(st, 0.0)
    kinetic_td = 0.5 * qd_td @ np.asarray(model.f_m(q_td, qd_td), float) @ qd_td
    assert kinetic_td > 10.0
    assert np.ptp(e) < 1e-6 * abs(e.mean())


def test_stance_is_time_symmetric():
    st = _one_stance()
    t = np.linspace(0.0, st["half_s"], 11)
    for tt in t:
        q1, qd1 = _stance_state(st, st["half_s"] - tt)
        q2, qd2 = _stance_state(st, st["half_s"] + tt)
        assert q1 == pytest.approx(q2, abs=1e-9) and qd1 == pytest.approx(-qd2, abs=1e-9)


def test_strict_recording_passes_the_analysis_with_every_hop_and_no_net_joint_work():
    from hop_impedance.discovery.forward_selection import measured_net_work_j
    from hop_impedance.discovery.measurement import measure_trial

    rec, truth = strict_recording(StrictConfig(hops=6, seed=5))
    trial = measure_trial(rec)
    assert len(trial.stances) == 6 and truth["effects"] == ["none"]
    tds = [h["t_td"] for h in truth["per_hop"]]
    assert [s.touchdown_s for s in trial.stances] == pytest.approx(tds, abs=0.005)
    w = np.array([measured_net_work_j(s) for s in trial.stances])
    assert abs(w.mean()) < 1.0


def test_one_joint_law_per_recording_unless_a_spread_is_asked_for():
    """The strict baseline is ``M = M_td + K phi`` with one K per recording (the outside generator's nulls: one
    ``kc`` per file, a different ``M_td`` per hop); ``stiffness_spread`` makes K vary by stance on purpose."""
    _, truth = strict_recording(StrictConfig(hops=3, seed=5))
    k0 = np.array([h["k0"] for h in truth["per_hop"]])
    m_td = np.array([h["M_td"] for h in truth["per_hop"]])
    assert np.ptp(k0, axis=0).max() == 0.0
    assert np.ptp(m_td, axis=0).min() > 0.1  # touchdown moments differ hop by hop
    _, spread = strict_recording(StrictConfig(hops=3, seed=5, stiffness_spread=0.2))
    k0s = np.array([h["k0"] for h in spread["per_hop"]])
    assert 0.0 < np.ptp(k0s / k0s.mean(axis=0), axis=0).max() < 0.8


def test_angle_dependent_stiffness_stays_a_stiffness_over_every_stance():
    """Seed 000's Eq. 7 (K >= 0) holds in the angle-dependent case: with ``k1 = k0`` per rad about mid-stance the
    stiffness at touchdown, ``k0 - k1 R``, is positive in every hop (the ankle's falls to 3-7 % of mid-stance's in
    seeds 0-3); with ``k1 = 1.5 k0`` it would be negative at the ankle (R 0.8-0.9 rad), and the generator refuses
    to draw such a stance instead of writing it (before: it wrote K down to -0.47 k0 at touchdown)."""
    _, truth = strict_recording(StrictConfig(hops=3, seed=1, angle_k1=1.0, angle_reference="mid-stance"))
    k_td = np.array([np.array(h["k0"]) - np.array(h["k1"]) * np.array(h["flex_mid_rad"]) for h in truth["per_hop"]])
    k1 = np.array([h["k1"] for h in truth["per_hop"]])
    assert np.all(k1 > 0.0)
    assert np.all(k_td > 0.0)
    # the hit-rate bench's size (bench/discovery_hit_rates.py STRICT_CASES): the ankle's K at touchdown is about a
    # third of its K at mid-stance, as in seed 000's Table 2 at 2.2 Hz (301 / (301 + 948 x 0.59) = 0.35)
    _, truth = strict_recording(StrictConfig(hops=4, seed=0, angle_k1=0.8, angle_reference="mid-stance"))
    ratio = np.array([1.0 - 0.8 * np.array(h["flex_mid_rad"]) for h in truth["per_hop"]])
    assert 0.25 < np.median(ratio[:, 0]) < 0.45
    assert np.all(ratio > 0.0)
    with pytest.raises(ValueError, match="no plausible stance"):
        strict_recording(StrictConfig(hops=1, seed=1, angle_k1=1.5, angle_reference="mid-stance"))


def test_touchdown_referenced_angle_law_has_one_touchdown_stiffness_per_recording():
    """Seed 000's Eq. 10 references k1 to the start of the stance; so does the default since session 18.

    The stiffness at touchdown ``k0 - k1 phi_mid`` (``k0`` the mid-stance form's, per stance) is the same number in
    every stance to 1e-6 N m/rad (the fixed point over ``phi_mid`` converged), ``k1 = 2.5 k_td`` per rad, and the
    touchdown-to-mid-stance ratio is seed-like at the ankle and knee (seed 000's Table 2 at 2.2 Hz: 0.35 / 0.49 / 0.64);
    K grows from touchdown, so it stays positive. The null is the same recording as before (k1 = 0 takes no iteration).
    """
    _, truth = strict_recording(StrictConfig(hops=4, seed=2, angle_k1=2.5))
    k0, k1, pm = (np.array([h[k] for h in truth["per_hop"]]) for k in ("k0", "k1", "flex_mid_rad"))
    k_td = k0 - k1 * pm
    np.testing.assert_allclose([h["k_touchdown"] for h in truth["per_hop"]], k_td, rtol=1e-12)
    assert np.ptp(k_td, axis=0).max() < 1e-6
    np.testing.assert_allclose(k1, 2.5 * k_td, rtol=1e-8)
    ratio = np.median(k_td / k0, axis=0)
    assert 0.28 < ratio[0] < 0.40 and 0.42 < ratio[1] < 0.56 and 0.6 < ratio[2] < 0.9
    assert np.all(k_td > 0.0)
    # a typical stance's mid-stance stiffness stays the recording's k0 (PHI_MID_TYPICAL scales k_td): within 15 %
    _, t_null = strict_recording(StrictConfig(hops=1, seed=2))  # the recording's k0 is drawn before any stance
    k_null = np.array(t_null["per_hop"][0]["k0"])
    assert np.all(np.abs(np.median(k0, axis=0) / k_null - 1.0) < 0.15)
    with pytest.raises(ValueError, match="angle_reference"):
        strict_recording(StrictConfig(hops=1, seed=1, angle_k1=1.0, angle_reference="take-off"))
