"""Issue 17's Table 1 rule as bench/simulator_issue17.py applies it (no simulation): which cells are binding,
their bands, and "at most 3 out, none of them stance time, peak GRF or the ankle"."""

from __future__ import annotations

import numpy as np
import pytest

from test.bench_import import bench_module


@pytest.fixture(scope="module")
def issue17():
    return bench_module("simulator_issue17")


def measures(issue17, factors: dict) -> dict:
    """Seed Table 1 itself times ``factors`` {(quantity, frequency): factor}, as the bench's measures (the COM drop:
    Newton's for the seed's peak GRF and stance, simulator_realism.newton_com_drop)."""
    out = {}
    newton_com_drop = bench_module("simulator_realism").newton_com_drop
    for f, seed in issue17.SEED_TABLE1.items():
        realism = {"stance_ms": seed["stance_ms"], "grf_bw": seed["grf_bw"], "hip_exc_m": seed["hip_exc_m"],
                   "com_drop_m": newton_com_drop(f, seed["stance_ms"] / 1000.0, seed["grf_bw"])[1],
                   "rom": np.array(seed["rom"], float), "mmax": np.array(seed["mmax"], float)}
        for (key, g, j), factor in factors.items():
            if g == f:
                if j is None:
                    realism[key] = realism[key] * factor
                else:
                    realism[key][j] *= factor
        out[f] = issue17.FrequencyMeasure(realism, {}, np.zeros((2, 3)), {}, {}, {})
    return out


def test_binding_cells_are_issue_17s_eight_per_frequency_with_its_bands(issue17):
    """Stance time, peak GRF, hip excursion 15 %; the three ranges of flexion 20 %; ankle and knee moment 25 %
    (the hip's moment is reported, not binding)."""
    rows, out = issue17.realism_rows(measures(issue17, {}))
    assert out == [] and all(r.passed for r in rows) and len(rows) == 9
    assert [r.band for r in rows[:-1]] == ["within 15%"] * 3 + ["within 20%"] * 3 + ["within 25%"] * 2
    assert not any("hip max moment" in r.criterion for r in rows)


def test_three_cells_out_pass_unless_one_is_stance_grf_or_ankle(issue17):
    allowed = {("hip_exc_m", 1.87, None): 0.7, ("hip_exc_m", 2.2, None): 0.84, ("mmax", 1.53, 1): 1.26}
    rows, out = issue17.realism_rows(measures(issue17, allowed))
    assert out == ["hip vertical excursion (m) at 1.87 Hz (cause: simulator_realism.OUT_CAUSES)",
                   "hip vertical excursion (m) at 2.2 Hz (cause: simulator_realism.OUT_CAUSES)",
                   "knee max moment (N m) at 1.53 Hz"]
    assert rows[-1].passed
    rows, out = issue17.realism_rows(measures(issue17, {("stance_ms", 2.2, None): 0.851}))  # inside the band
    assert out == [] and rows[-1].passed
    for forbidden in (("stance_ms", 2.2, None), ("grf_bw", 1.53, None), ("rom", 1.87, 0), ("mmax", 2.2, 0)):
        rows, out = issue17.realism_rows(measures(issue17, {forbidden: 0.7}))
        assert len(out) == 1 and not rows[-1].passed, forbidden
    rows, out = issue17.realism_rows(measures(issue17, {**allowed, ("rom", 1.53, 2): 0.5}))
    assert len(out) == 4 and not rows[-1].passed


def test_bell_shape_failure_names_the_edge_or_the_sign(issue17):
    """K(t) = 300 + 200 sin^2(pi t): a bell with non-zero edges; rising to take-off: maximum at the edge; a bell
    whose take-off edge goes negative: the sign."""
    t = np.linspace(0.0, 1.0, 101)
    assert issue17.bell_shape_failure(300.0 + 200.0 * np.sin(np.pi * t) ** 2) == ""
    assert issue17.bell_shape_failure(300.0 + 200.0 * t).startswith("maximum at the take-off edge")
    why = issue17.bell_shape_failure(300.0 * np.sin(np.pi * t) ** 2 + 100.0 - 150.0 * t)
    assert why.startswith("K on the K >= 0 bound at an edge") and "take-off -50" in why


def test_bell_edge_on_the_bound_is_zero_whatever_its_sign(issue17):
    """Session 20: a take-off edge the QP holds on K >= 0 is a zero edge at +1e-6 as at -1e-6 N m/rad (the row used to
    count the first as non-zero); an edge below 1 % of the maximum is on the bound, one of 2-4 % is not (the
    preset's knee edges off the bound are 56-142 N m/rad, bench/simulator_knee_bell.py)."""
    t = np.linspace(0.0, 1.0, 101)
    bell = 200.0 + 200.0 * np.sin(np.pi * t) ** 2  # maximum 400
    for edge in (1e-6, -1e-6, 0.0, 1.5):
        k = bell - (bell[-1] - edge) * t  # same touchdown, take-off edge = edge
        assert k[-1] == pytest.approx(edge) and 200.0 < k.max() < 400.0
        assert issue17.bell_shape_failure(k).startswith("K on the K >= 0 bound at an edge"), edge
    k = bell - (bell[-1] - 8.0) * t
    assert issue17.bell_shape_failure(k) == ""


def test_fig7_diagnosis_names_the_point_off_the_line(issue17):
    """Nine points on y = 2 x except the knee at 1.87 Hz: its r^2 without it is 1, every other's below 1."""
    ms = {}
    for f in issue17.FREQS:
        k = {j: (100.0 * (i + 1) * f, 200.0 * (i + 1) * f) for i, j in enumerate(issue17.JOINTS)}
        if f == 1.87:
            k["knee"] = (k["knee"][0], 3.0 * k["knee"][1])
        ms[f] = issue17.FrequencyMeasure({}, {}, np.zeros((2, 3)), {}, {}, k)
    lines = issue17.diagnosis(ms)
    without = {ln.split(":")[0].strip(): float(ln.rsplit(" ", 1)[1]) for ln in lines[1:10]}
    assert without["knee 1.87 Hz"] == pytest.approx(1.0)
    assert all(v < 0.99 for k, v in without.items() if k != "knee 1.87 Hz")


def fit_measures(issue17, knee_bell: dict) -> dict:
    """Measures that pass every fit row except, perhaps, the knee's bell: its share per frequency from ``knee_bell``."""
    out = {}
    for f in issue17.FREQS:
        k = {j: (100.0 * (i + 1) * f, 200.0 * (i + 1) * f) for i, j in enumerate(issue17.JOINTS)}
        out[f] = issue17.FrequencyMeasure({}, {j: (10, 10) for j in issue17.JOINTS}, issue17.table2_k(f),
                                          {"ankle": 1.0, "knee": knee_bell[f], "hip": 0.0},
                                          {j: (1.0, 2.0) for j in issue17.JOINTS}, k)
    return out


def test_bell_row_reads_issue_17s_share_of_stances(issue17):
    """Session 20: the bell row asks >= 80 % of the stances (the seed's "Typically", issue 17's ">= 80 % of stances"),
    not every stance: 8 of 9 stances pass, 7 of 9 (this branch's 1.87 Hz knee) and 5 of 9 (its 2.2 Hz) fail."""
    assert issue17.BELL_SHARE == 0.8
    rows = {r.criterion: r for r in issue17.fit_rows(fit_measures(issue17, {1.53: 1.0, 1.87: 8 / 9, 2.2: 8 / 9}))}
    knee = rows["K(t) bell-shaped with non-zero edges, knee"]
    assert knee.passed and knee.band == ">= 80% of stances" and knee.measured == "1.53 Hz 100%, 1.87 Hz 89%, 2.2 Hz 89%"
    assert all(r.passed for r in rows.values())  # Fig. 7's nine points on y = 2 x: r^2 1
    rows = {r.criterion: r for r in issue17.fit_rows(fit_measures(issue17, {1.53: 1.0, 1.87: 7 / 9, 2.2: 5 / 9}))}
    assert not rows["K(t) bell-shaped with non-zero edges, knee"].passed
    assert rows["K(t) bell-shaped with non-zero edges, ankle"].passed


def test_flight_flag_sets_the_flight_model(issue17):
    """``--flight prescribed`` (the preset's flight of sessions 14-31) changes only the preset's flight model, which is
    the trunk-still one since session 33."""
    base, _ = issue17.variant_options(issue17.VariantArgs(hopper="seed-like", law_scale="none", surface="rigid"))
    options, said = issue17.variant_options(issue17.VariantArgs(hopper="seed-like", law_scale="none", surface="rigid",
                                                                flight="prescribed"))
    assert base["flight"] == "trunk_still" and options["flight"] == "prescribed" and said.endswith("flight prescribed")
    assert {k: v for k, v in options.items() if k != "flight"} == {k: v for k, v in base.items() if k != "flight"}


def test_the_flight_row_reads_the_truths_energy_budget(issue17):
    """Issue 17's flight criterion from a truth file's per-stance budgets: the bundled 2.2 Hz recording (session 33's
    preset, trunk-still flight) keeps the energy in flight to round-off (|flight_j| at most 2.3e-13 J of about
    570 J) and its push-off does 10.4 J per hop (7.1-12.2); a flight that discards 1 J of 570 fails the row."""
    from pathlib import Path

    from hop_impedance.simulation.truth import load_truth

    truth = load_truth(Path(__file__).resolve().parents[2] / "recordings" / "sim_2p20hz_hard.truth.json")
    energy = issue17.flight_energy(truth)
    assert energy["flight_rel"] < 1e-15
    assert energy["push_off_j"] == pytest.approx((10.37, 7.11, 12.22), abs=0.05)
    measures = {2.2: issue17.FrequencyMeasure({}, {}, None, {}, {}, {}, {}, energy)}
    assert issue17.energy_rows(measures)[0].passed
    lossy = {**truth, "stances": [{**s, "energy_j": {**s["energy_j"], "flight_j": -1.0}} for s in truth["stances"]]}
    measures = {2.2: issue17.FrequencyMeasure({}, {}, None, {}, {}, {}, {}, issue17.flight_energy(lossy))}
    row = issue17.energy_rows(measures)[0]
    assert not row.passed and row.measured.startswith("2.2 Hz 1.8e-03")


def test_one_trial_for_table1(issue17):
    """The realism table, issue 17's table and the bundled Table 1 recordings read one trial length (session 34: the
    realism bench read 6 hops and issue 17's 10, and the two disagreed on the 1.53 Hz hip range, -20 % against -19 %)."""
    import inspect
    import pathlib
    import re

    realism = bench_module("simulator_realism")
    hops = realism.TABLE1_TRIAL_HOPS
    for function in (realism.measure, realism.measure_hopper, issue17.measure_frequency, issue17.criteria):
        assert inspect.signature(function).parameters["hops"].default == hops, function.__name__
    script = (pathlib.Path(__file__).resolve().parents[2] / "recordings" / "regenerate.sh").read_text()
    table1 = [line for line in script.splitlines() if "--hopper seed-like" in line]
    assert len(table1) == 3 and all(re.search(rf"--hops {hops}\b", line) for line in table1)
