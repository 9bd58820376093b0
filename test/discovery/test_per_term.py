"""``forward_selection.PER_TERM`` (session 37; an option, off by default): the held-out screen may also pass a candidate
that is significantly better on one of the gap's ten terms (:data:`~hop_impedance.discovery.forward.GAP_TERMS`).

Checked: each simulated stance's ten squared scaled terms average to its gap; on our simulator's plate offset (+20 N,
as in docs/discovery.md "Session 37") the flight term carries the offset and the fitted offset removes it; the
per-term test passes a flight-only improvement that the total's t-test misses, ties count as zero, and
:func:`~hop_impedance.discovery.forward_selection.passes` reads the test only when it was made.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery.forward import GAP_SIGNALS, GAP_TERMS
from hop_impedance.discovery.identify import identify
from hop_impedance.discovery.measurement import measure_trial, weight_n
from hop_impedance.discovery.model import ModelSpec
from hop_impedance.simulation.scenarios import Effects
from hop_impedance.simulation.sensors import SensorConfig
from hop_impedance.simulation.stance_set import simulate_stance_set_recording

OFFSET_N = 20.0
_CACHE: dict = {}


def offset_trial():
    """Our simulator, baseline law on hard ground (2.2 Hz, seed 1, 5 hops), the plate reading +20 N throughout."""
    if not _CACHE:
        rec, _ = simulate_stance_set_recording(2.2, ("hard",), 5, 1, Effects(angle_dependent_stiffness=False,
                                               damping=False, push_off=False), SensorConfig(force_offset_n=OFFSET_N),
                                               rtol=1e-6, redraws=10)
        _CACHE["trial"] = measure_trial(rec)
    return _CACHE["trial"]


def test_the_ten_terms_are_the_seven_signals_then_duration_work_and_flight():
    assert len(GAP_TERMS) == 10 and GAP_TERMS[:7] == GAP_SIGNALS
    assert GAP_TERMS[7:] == ("duration", "net_work", "flight_force")


def test_a_stance_s_terms_average_to_its_gap_and_the_flight_term_carries_the_plate_offset():
    """Stance 2 simulated with the baseline (offset 0) and with the fitted offset: ``mean(term_errors) == gap``; the
    flight term is (20 N / (0.1 W))^2 without the offset and below 1 % of that with it."""
    trial = offset_trial()
    scales = fs.gap_scales(trial)
    base, coefs = identify(ModelSpec(), trial, trial.stances, None)
    shifted, coefs_off = identify(ModelSpec(), trial, trial.stances, "force_plate_offset")
    assert shifted.offset_n == pytest.approx(OFFSET_N, abs=1.0)
    s = trial.stances[2]
    runs = [fs.simulate_held_out(m, c, trial, s, scales, samples=True) for m, c in ((base, coefs), (shifted, coefs_off))]
    for r in runs:
        assert r["end_reason"] == "take_off" and r["term_errors"].shape == (10,)
        assert np.mean(r["term_errors"]) == pytest.approx(r["gap"], rel=1e-12)
        assert r["term_errors"][7:] == pytest.approx(r["terms"] ** 2, rel=1e-12)
    expected = (np.mean(s.flight_fz_n) / (fs.FLIGHT_SCALE_BW * weight_n(trial))) ** 2
    assert np.mean(s.flight_fz_n) == pytest.approx(OFFSET_N, abs=1.0)
    assert runs[0]["term_errors"][9] == pytest.approx(expected, rel=1e-9)
    assert runs[1]["term_errors"][9] < 0.01 * runs[0]["term_errors"][9]


#: Per stance the factor by which the candidate changes the nine shared terms: no net direction, wide scatter.
SHARED_LOG_FACTOR = np.array([-1.0, -0.7, -0.3, 0.0, 0.0, 0.3, 0.7, 1.0])


def _flight_only(n: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Ten terms per stance: the nine shared ones 0.01 for the current model and 0.01 e^SHARED_LOG_FACTOR for the
    candidate; the flight term 0.08 (20 N over 0.1 W of a 71 kg subject, squared) against ~1e-4."""
    cur = np.full((n, 10), 0.01)
    cand = cur * np.exp(np.resize(SHARED_LOG_FACTOR, n))[:, None]
    cur[:, 9] = 0.08
    cand[:, 9] = 1e-4 * np.exp(np.resize([0.1, -0.2, 0.3, -0.1, 0.0, 0.2, -0.3, 0.1], n))
    return cur, cand


def test_a_flight_only_improvement_passes_per_term_but_not_the_total_test():
    """The total's log ratios are 0.64 - SHARED_LOG_FACTOR (about -0.4 .. 1.6): p above 0.05 / 8 though the pooled gap
    shrinks; per term the flight is better in every stance and no shared term is worse (p 0.5 both ways)."""
    cur, cand = _flight_only()
    d, shrink, p = fs.compare_gaps(cur.mean(axis=1), cand.mean(axis=1))
    assert shrink >= fs.MIN_SHRINK and not fs.significant(p, shrink, 8) and 0.05 / 8 < p < 0.05
    out = fs.per_signal_test(cur, cand, shrink, 8, GAP_TERMS)
    assert set(out["signals"]) == set(GAP_TERMS) and out["level"] == pytest.approx(0.05 / 80)
    assert out["signals"]["flight_force"]["p_better"] < 1e-8
    assert all(out["signals"][k]["p_worse"] == pytest.approx(0.5) for k in GAP_TERMS[:9])
    assert out["passes"]


def test_ties_are_zero_and_a_worse_term_blocks():
    cur, cand = _flight_only()
    cur[:, 3] = cand[:, 3] = 0.0  # a term both models get exactly right: no evidence either way
    cand[:4, 8] = np.nan  # candidate failed on 4 stances' work term: capped log ratios, significantly worse
    out = fs.per_signal_test(cur, cand, 0.5, 8, GAP_TERMS)
    assert out["signals"]["angle_hip"]["per_stance_log_ratio"] == [0.0] * 8
    assert out["signals"]["net_work"]["p_worse"] < 0.05 and not out["passes"]


def _score(p: float, admissible: bool, per_term: dict | None) -> fs.ForwardScore:
    runs = fs.HeldOutRuns(None, ModelSpec(), np.ones(8), np.ones((8, 7)), np.zeros(8), np.zeros(8), ["take_off"] * 8)
    return fs.ForwardScore("force_plate_offset", runs, np.zeros(8), 0.3, 0.3, p, admissible, {}, per_term)


def test_passes_reads_the_per_term_test_only_when_made_and_never_past_physics():
    assert not fs.passes(_score(0.02, True, None), 8)  # 0.02 > 0.05 / 8: the total test alone
    assert fs.passes(_score(0.02, True, {"passes": True}), 8)
    assert not fs.passes(_score(0.02, True, {"passes": False}), 8)
    assert not fs.passes(_score(1e-6, False, {"passes": True}), 8)  # inadmissible physics blocks either way
    assert fs.passes(_score(1e-6, True, None), 8)


def test_score_makes_the_per_term_test_only_with_the_option(monkeypatch):
    trial = offset_trial()
    cur, cand = _flight_only(len(trial.stances))
    n = len(trial.stances)

    def runs(effect, terms):
        return fs.HeldOutRuns(effect, ModelSpec(), terms.mean(axis=1), np.ones((n, 7)), np.zeros(n), np.zeros(n),
                              ["take_off"] * n, term_errors=terms)

    current, offset = runs(None, cur), runs("force_plate_offset", cand)
    assert fs.PER_TERM is False and fs.score(trial, current, [offset], 8)[0].per_term is None
    monkeypatch.setattr(fs, "PER_TERM", True)
    (sc,) = fs.score(trial, current, [offset], 8)
    assert sc.per_term is not None and sc.per_term["level"] == pytest.approx(0.05 / 80)
    assert sc.per_term["signals"]["flight_force"]["p_better"] < 1e-4
    assert fs.score(trial, current, [dataclasses.replace(offset, term_errors=None)], 8)[0].per_term is None
