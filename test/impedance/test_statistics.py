"""Tables and Wilcoxon tests across stances and conditions."""

from __future__ import annotations

import numpy as np
from conftest import fit_synthetic
from scipy import stats

from hop_impedance.impedance.statistics import (
    StanceFitRecord,
    markdown_table,
    mean_sd,
    table2,
    table3,
    wilcoxon_between_conditions,
    wilcoxon_variable_vs_constant,
)
from hop_impedance.impedance.synthetic import synthetic_stance


def records():
    out = []
    for freq in ("1.53", "2.20"):
        for s in range(6):
            for joint in ("ankle", "knee", "hip"):
                st = synthetic_stance(joint, float(freq), np.random.default_rng(s), realistic_noise=True)
                out.append(StanceFitRecord(freq, f"S{s}", joint, fit_synthetic(st)))
    return out


def test_tables_and_tests_on_two_frequencies():
    recs = records()
    t2 = table2(recs, ["1.53", "2.20"])
    ankle_avg = [row for row in t2 if row[:2] == ["ankle", "Average (N m/rad)"]][0]
    lo, hi = (float(cell.split()[0]) for cell in ankle_avg[2:])
    assert lo < hi  # stiffness rises with frequency
    n, p = wilcoxon_between_conditions(recs, "ankle", "average_stiffness", "1.53", "2.20")
    assert n == 6 and p == stats.wilcoxon([1, 2, 3, 4, 5, 6], [7, 8, 9, 10, 11, 12]).pvalue  # all pairs one-sided
    n, p = wilcoxon_variable_vs_constant(recs, "knee", "2.20")
    assert n == 6 and p < 0.05
    t3 = table3(recs, ["2.20"])
    assert [r[1] for r in t3] == ["variable stiffness", "constant stiffness"]
    text = markdown_table(["joint", "quantity", "1.53", "2.20"], t2)
    assert text.count("\n") == len(t2) + 2


def test_mean_sd_format():
    assert mean_sd([1.0, 2.0, 3.0]) == "2.0 (1.0)"
    assert mean_sd([float("nan")]) == "-"
