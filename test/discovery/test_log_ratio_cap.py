"""``forward_selection.LOG_RATIO_CAP`` (session 16, the default): the t-tests see every per-stance log gap ratio clipped.

The ratios are shaped like session 15's angle + offset recording of our simulator (all 8 positive, 0.38-6.1, the
6.1 a stance the current model failed outright); the p-values are computed here by scipy, not pinned stubs.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from hop_impedance.discovery import forward_selection as fs

#: Per-stance log gap ratios, current over candidate.
D = np.array([0.38, 0.5, 0.6, 0.8, 1.0, 1.3, 1.6, 6.1])
LOG10 = float(np.log(10.0))


def gaps() -> tuple[np.ndarray, np.ndarray]:
    cand = np.full(D.size, 0.04)
    return cand * np.exp(D), cand


def test_without_cap_one_failed_stance_hides_eight_positive_ratios(monkeypatch):
    monkeypatch.setattr(fs, "LOG_RATIO_CAP", None)
    d, shrink, p = fs.compare_gaps(*gaps())
    np.testing.assert_allclose(d, D, atol=1e-12)
    assert p == pytest.approx(stats.ttest_1samp(D, 0.0, alternative="greater").pvalue, rel=1e-12)
    assert p == pytest.approx(0.0276, abs=5e-5)  # above the Bonferroni level of 8 candidates, 0.00625
    assert not fs.significant(p, shrink, 8)


def test_cap_at_log10_names_it_and_reports_the_ratios_uncapped(monkeypatch):
    monkeypatch.setattr(fs, "LOG_RATIO_CAP", LOG10)
    d, shrink, p = fs.compare_gaps(*gaps())
    assert d[-1] == pytest.approx(6.1)  # reported as measured; only the test's input is clipped
    assert p == pytest.approx(stats.ttest_1samp(np.minimum(D, LOG10), 0.0, alternative="greater").pvalue, rel=1e-12)
    assert p == pytest.approx(0.00122, abs=5e-6)  # < 0.05 / 8
    assert fs.significant(p, shrink, 8)


def test_cap_keeps_a_failed_candidate_stance_a_loss_of_one_order(monkeypatch):
    monkeypatch.setattr(fs, "LOG_RATIO_CAP", LOG10)
    cur, cand = gaps()
    cand[0] = np.inf  # the candidate's simulation of stance 0 failed
    d, _, p = fs.compare_gaps(cur, cand)
    assert d[0] == -np.inf
    np.testing.assert_allclose(fs.capped(d), np.r_[-LOG10, D[1:-1], LOG10])
    assert p == pytest.approx(stats.ttest_1samp(fs.capped(d), 0.0, alternative="greater").pvalue, rel=1e-12)
    assert p > 0.05 / 8  # one lost stance costs the candidate its significance here


def test_ambiguous_with_compares_the_capped_ratios(monkeypatch):
    """Without the cap the winner's one huge ratio (6.1 against the runner-up's 1.0) makes the paired differences
    so spread that the runner-up is reported ambiguous although the winner is ahead on every other stance; capped,
    the differences are 0.08-0.32 on seven stances and 1.3 on the eighth, and it is not."""
    runner_up = np.r_[0.8 * D[:-1], 1.0]

    def score(effect, d):
        runs = fs.HeldOutRuns(effect, None, np.ones(8), np.zeros((8, 7)), np.zeros(8), np.zeros(8), [])  # type: ignore[arg-type]
        return fs.ForwardScore(effect, runs, d, float(np.mean(d)), 0.5, 1e-4, True, {})

    best, other = score("angle_dependent_stiffness", D), score("time_dependent_activation", runner_up)
    monkeypatch.setattr(fs, "LOG_RATIO_CAP", None)
    amb = fs.ambiguous_with(best, [best, other])
    assert [a["effect"] for a in amb] == ["time_dependent_activation"]
    assert amb[0]["p_value_difference"] == pytest.approx(0.1198, abs=1e-4)
    monkeypatch.setattr(fs, "LOG_RATIO_CAP", LOG10)
    assert fs.ambiguous_with(best, [best, other]) == []
    p = stats.ttest_1samp(np.minimum(D, LOG10) - runner_up, 0.0, alternative="greater").pvalue
    assert p == pytest.approx(0.0315, abs=1e-4)  # < ALPHA: the winner is significantly ahead


def test_an_infinite_cap_is_the_uncapped_test_of_sessions_1_to_15(monkeypatch):
    """``--log-ratio-cap inf``: the same p as without the cap, failed stances (+-inf) included (200 draws)."""
    rng = np.random.default_rng(1)
    for k in range(200):
        d = rng.normal(0.5, 3.0, 8)
        if k % 3 == 0:
            d[k % 8] = np.inf
        if k % 5 == 0:
            d[(k + 1) % 8] = -np.inf
        monkeypatch.setattr(fs, "LOG_RATIO_CAP", None)
        p_none = fs.one_sided_t(fs.capped(d))
        monkeypatch.setattr(fs, "LOG_RATIO_CAP", float("inf"))
        assert fs.one_sided_t(fs.capped(d)) == p_none
