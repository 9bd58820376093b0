"""Issue 17's Fig. 7 row (r^2 >= 0.9) against the seed's own tables (session 13, bench/simulator_fig7.py).

Seed Table 2's reduced law K = k0 + k1 (rho - rho0) driven through seed Table 1's ranges of flexion has initial
stiffness k0 and maximal k0 + k1 x range (every k1 > 0); the nine joint x frequency points lie on a line with
r^2 0.895, under issue 17's 0.9 (the seed's Fig. 7 reports 0.95 for its measured mean maxima).
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.simulation.scenarios import SEED_TABLE2
from test.bench_import import bench_module


def bench_modules():
    return bench_module("simulator_fig7"), bench_module("simulator_realism").SEED_TABLE1


def test_table2_law_through_table1_ranges_misses_r2_09():
    """Recomputed here with numpy's correlation from the two tables (independent of fig7_line): r^2 0.895."""
    fig7, table1 = bench_modules()
    x, y = [], []
    for f, row in table1.items():
        t2 = SEED_TABLE2[min(SEED_TABLE2, key=lambda g: abs(g - f))]
        for j in range(3):
            assert t2["k1"][j] > 0
            x.append(t2["k0"][j])
            y.append(t2["k0"][j] + t2["k1"][j] * row["rom"][j])
    r2 = np.corrcoef(x, y)[0, 1] ** 2
    assert r2 == pytest.approx(0.895, abs=5e-4)
    assert r2 < 0.9
    points = fig7.law_points()
    assert np.allclose(sorted(p[:2] for p in points.values()), sorted(zip(x, y)))
    assert fig7.leave_one_out(points)[(2.2, "ankle")] == pytest.approx(0.794, abs=5e-4)  # the 2.2 Hz ankle holds the line
