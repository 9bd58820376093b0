"""Population report of a batch: the seed's Table 1/2/3 layouts by condition, tests paired by subject, figures.

Choice (the seed: "Mean (SD), n = 8" subjects): every cell is the mean (SD)
over subjects of each subject's mean over its stances in that condition, so a
subject with 40 stances weighs as much as one with 10, and n is the number of
subjects. Between-condition tests are Wilcoxon signed-rank tests on those
subject means, paired by subject
(:func:`~hop_impedance.impedance.statistics.wilcoxon_between_conditions` with
``pair_by="subject"``), for every pair of conditions (the seed compares low
vs medium, medium vs high and low vs high); never by stance order. The
variable vs constant stiffness error test stays paired by stance (both models
are fitted to the same stance). Figures are those of ``analyze --report``
(:func:`~hop_impedance.impedance.report.write_figures`).

Table 1 (the seed's kinematics and kinetics: peak GRF, stance time, hip
excursion, range of flexion, maximal moment, brake and push energy) comes from
stances with inverse dynamics; Tables 2 and 3 from usable fits.
"""

from __future__ import annotations

import itertools
import math
import re
import warnings
from pathlib import Path

import numpy as np

from hop_impedance.impedance.regression_model import TERM_NAMES
from hop_impedance.impedance.report import JOINTS, _write_csv, write_figures
from hop_impedance.impedance.stance_fit import JointImpedanceFit
from hop_impedance.impedance.statistics import (
    TABLE2_QUANTITIES,
    StanceFitRecord,
    markdown_table,
    quantity,
    table2,
    table3,
    wilcoxon_between_conditions,
    wilcoxon_variable_vs_constant,
)

#: Table 1 rows: (label, tidy column, per joint?, scale, decimals as in the seed's Table 1).
TABLE1_QUANTITIES: tuple[tuple[str, str, bool, float, int], ...] = (
    ("Peak GRF (BW)", "peak_grf_bw", False, 1.0, 2),
    ("Stance time (ms)", "contact_time_s", False, 1000.0, 0),
    ("Vertical excursion of hip (m)", "hip_excursion_m", False, 1.0, 3),
    ("Range of flexion (rad)", "range_of_flexion_rad", True, 1.0, 2),
    ("Maximal moment (N m)", "max_moment_nm", True, 1.0, 1),
    ("Brake phase energy (J)", "brake_work_j", True, 1.0, 1),
    ("Push phase energy (J)", "push_work_j", True, 1.0, 1),
)


def condition_order(conditions) -> list[str]:
    """Conditions sorted by their leading number when they have one ("1.53 Hz" < "2.20 Hz"), else by name."""

    def key(c: str):
        m = re.match(r"\s*([-+]?\d+(?:\.\d*)?)", c)
        return (0, float(m.group(1)), c) if m else (1, 0.0, c)

    return sorted(set(conditions), key=key)


def subject_means(pairs) -> list[float]:
    """Each subject's mean of its finite values, from ``(subject, value)`` pairs (subjects sorted)."""
    by: dict[str, list[float]] = {}
    for sid, v in pairs:
        if v is not None and math.isfinite(v):
            by.setdefault(sid, []).append(v)
    return [float(np.mean(by[s])) for s in sorted(by)]


def table1(rows: list[dict], conditions: list[str]) -> list[list[str]]:
    """Rows ``[quantity, joint, mean (SD) over subjects per condition...]`` (seed Table 1 layout)."""
    stance_rows = [r for r in rows if not math.isnan(r["range_of_flexion_rad"])]
    out = []
    for label, column, per_joint, scale, digits in TABLE1_QUANTITIES:
        for joint in JOINTS if per_joint else ("ankle",):  # stance figures repeat on each joint's row
            row = [label, joint if per_joint else ""]
            for c in conditions:
                sel = [(r["subject"], r[column] * scale) for r in stance_rows if r["condition"] == c and r["joint"] == joint]
                m = subject_means(sel)
                sd = float(np.std(m, ddof=1)) if len(m) > 1 else 0.0
                # statistics.mean_sd has one decimal (Table 2/3); Table 1 needs the seed's 0-3
                row.append(f"{np.mean(m):.{digits}f} ({sd:.{digits}f})" if m else "-")
            out.append(row)
    return out


def subject_records(records: list[StanceFitRecord]) -> list[StanceFitRecord]:
    """One record per (condition, subject, joint) whose fit holds that subject's mean over its stances of
    every Table 2/3 quantity, so :func:`statistics.table2`/:func:`statistics.table3` give mean (SD) over subjects."""
    groups: dict[tuple[str, str, str], list] = {}
    for r in records:
        groups.setdefault((r.condition, r.subject_id, r.joint), []).append(r.fit)
    out = []
    for (condition, subject, joint), fits in groups.items():
        means = {name: (subject_means((subject, quantity(f, name)) for f in fits) or [math.nan])[0]
                 for name in [n for _, n in TABLE2_QUANTITIES] + ["table3_variable", "table3_constant"]}
        statistics: dict = {n: v for n, v in means.items() if n not in TERM_NAMES}  # the fit's named statistics
        fit = JointImpedanceFit(status="solved", rejection_reason=None,
                                coefficients={n: v for n, v in means.items() if n in TERM_NAMES}, **statistics)
        out.append(StanceFitRecord(condition, subject, joint, fit))
    return out


def paired_tests(records: list[StanceFitRecord], conditions: list[str]) -> list[list[str]]:
    """Rows ``[conditions, joint, quantity, pairing, pairs, p]``: Table 2 quantities between every
    pair of conditions paired by subject; variable vs constant error per condition paired by stance.
    Where every difference is zero (a term no subject kept) scipy's p is NaN; its warning is silenced."""
    tests = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for a, b in itertools.combinations(conditions, 2):
            for joint in JOINTS:
                for _, name in TABLE2_QUANTITIES:
                    n, p = wilcoxon_between_conditions(records, joint, name, a, b, pair_by="subject")
                    tests.append([f"{a} vs {b}", joint, name, "subject", str(n), f"{p:.3g}"])
        for c in conditions:
            for joint in JOINTS:
                n, p = wilcoxon_variable_vs_constant(records, joint, c)
                tests.append([c, joint, "SSE variable vs constant", "stance", str(n), f"{p:.3g}"])
    return tests


def counts(rows: list[dict], records: list[StanceFitRecord], conditions: list[str]) -> list[list[str]]:
    """Rows ``[condition, joint, subjects, recordings, usable fits]``."""
    out = []
    for c in conditions:
        for joint in JOINTS:
            sel = [r for r in records if r.condition == c and r.joint == joint]
            recs = {r["recording"] for r in rows if r["condition"] == c}
            out.append([c, joint, str(len({r.subject_id for r in sel})), str(len(recs)), str(len(sel))])
    return out


def write_population_report(rows: list[dict], records: list[StanceFitRecord], out_dir: Path) -> list[Path]:
    """Write table1/2/3.csv, tests.csv, report.md and the figures into ``out_dir``; returns every file."""
    out_dir.mkdir(parents=True, exist_ok=True)
    conditions = condition_order(r["condition"] for r in rows)
    h1, h2, h3 = ["quantity", "joint"] + conditions, ["joint", "quantity"] + conditions, ["condition", "model", *JOINTS]
    ht = ["conditions", "joint", "quantity", "paired by", "pairs", "p"]
    hc = ["condition", "joint", "subjects", "recordings", "usable fits"]
    per_subject = subject_records(records)
    t1, t2, t3 = table1(rows, conditions), table2(per_subject, conditions), table3(per_subject, conditions)
    tests, n = paired_tests(records, conditions), counts(rows, records, conditions)
    paths = [out_dir / f for f in ("table1.csv", "table2.csv", "table3.csv", "tests.csv", "counts.csv")]
    for path, header, body in zip(paths, (h1, h2, h3, ht, hc), (t1, t2, t3, tests, n)):
        _write_csv(path, header, body)
    md = out_dir / "report.md"
    md.write_text(
        "# Population report\n\nEvery cell: mean (SD) over subjects of each subject's mean over its stances "
        "(the seed's n = subjects). Tests: Wilcoxon signed-rank, two-sided.\n\n"
        "## Subjects, recordings and usable fits\n\n" + markdown_table(hc, n)
        + "\n## Table 1 layout: stance kinematics and kinetics\n\n" + markdown_table(h1, t1)
        + "\n## Table 2 layout: stiffness\n\n" + markdown_table(h2, t2)
        + "\n## Table 3 layout: error SSE * 1e-3 / N * FR\n\n" + markdown_table(h3, t3)
        + "\n## Tests\n\n" + markdown_table(ht, tests),
        encoding="utf-8",
    )
    return paths + [md] + write_figures(records, conditions, out_dir)


__all__ = ["TABLE1_QUANTITIES", "condition_order", "counts", "paired_tests", "subject_means", "subject_records",
           "table1", "write_population_report"]
