"""Mean (SD) tables in the layout of the seed's Tables 2-3 and Wilcoxon tests.

Input is a flat list of :class:`StanceFitRecord` (one per joint per usable
stance). Conditions are labels such as hopping frequencies ("1.53").
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import stats

from hop_impedance.impedance.stance_fit import JointImpedanceFit

#: Table 2 rows per joint: (label, attribute of JointImpedanceFit or coefficient name).
TABLE2_QUANTITIES: tuple[tuple[str, str], ...] = (
    ("Overall (N m/rad)", "overall_stiffness"),
    ("Average (N m/rad)", "average_stiffness"),
    ("k0 (N m/rad)", "k0"),
    ("k1 (N m/rad^2)", "k1"),
)


@dataclass(frozen=True)
class StanceFitRecord:
    """One usable fit with its grouping keys.

    Attributes
    ----------
    condition : str
        e.g. the hopping frequency label.
    subject_id : str
        Pairing key for between-condition tests.
    joint : str
    fit : JointImpedanceFit
    """

    condition: str
    subject_id: str
    joint: str
    fit: JointImpedanceFit


def quantity(fit: JointImpedanceFit, name: str) -> float:
    """A Table 2/3 quantity of one fit (coefficients absent from the model count as 0)."""
    if name in ("k0", "k1", "k2", "k3", "b0", "b1", "b2", "b3"):
        return float(fit.coefficients.get(name, 0.0))
    return float(getattr(fit, name))


def mean_sd(values: Iterable[float]) -> str:
    """``"mean (SD)"`` with one decimal (sample SD, ddof=1; "-" when empty)."""
    v = np.asarray([x for x in values if np.isfinite(x)], float)
    if v.size == 0:
        return "-"
    sd = v.std(ddof=1) if v.size > 1 else 0.0
    return f"{v.mean():.1f} ({sd:.1f})"


def table2(records: list[StanceFitRecord], conditions: list[str]) -> list[list[str]]:
    """Rows ``[joint, quantity, mean (SD) per condition...]`` (seed Table 2 layout)."""
    rows = []
    for joint in ("ankle", "knee", "hip"):
        for label, name in TABLE2_QUANTITIES:
            row = [joint, label]
            for c in conditions:
                row.append(mean_sd(quantity(r.fit, name) for r in records if r.joint == joint and r.condition == c))
            rows.append(row)
    return rows


def table3(records: list[StanceFitRecord], conditions: list[str]) -> list[list[str]]:
    """Rows ``[condition, model, ankle, knee, hip]`` of the Table 3 error metric."""
    rows = []
    for c in conditions:
        for model, name in (("variable stiffness", "table3_variable"), ("constant stiffness", "table3_constant")):
            row = [c, model]
            for joint in ("ankle", "knee", "hip"):
                row.append(mean_sd(getattr(r.fit, name) for r in records if r.joint == joint and r.condition == c))
            rows.append(row)
    return rows


def wilcoxon_between_conditions(
    records: list[StanceFitRecord], joint: str, name: str, condition_a: str, condition_b: str, pair_by: str = "subject"
) -> tuple[int, float]:
    """Wilcoxon signed-rank test of a quantity between two conditions.

    Parameters
    ----------
    records : list of StanceFitRecord
    joint, name : str
        Joint and quantity (see :func:`quantity`).
    condition_a, condition_b : str
    pair_by : {"subject", "stance"}
        ``"subject"``: per-subject means paired by subject (the seed's repeated
        measures). ``"stance"``: the i-th stance of each condition paired (one
        subject, several stances; a pragmatic pairing).

    Returns
    -------
    n_pairs : int
    p_value : float
        Two-sided; NaN when fewer than 2 pairs.
    """
    def values(c: str) -> list[tuple[str, float]]:
        return [(r.subject_id, quantity(r.fit, name)) for r in records if r.joint == joint and r.condition == c]

    a, b = values(condition_a), values(condition_b)
    xa: list[float | np.floating[Any]]  # per-subject means (numpy scalars) or the stances' own values
    xb: list[float | np.floating[Any]]
    if pair_by == "subject":
        subjects = sorted({s for s, _ in a} & {s for s, _ in b})
        xa = [np.mean([v for s, v in a if s == sid]) for sid in subjects]
        xb = [np.mean([v for s, v in b if s == sid]) for sid in subjects]
    elif pair_by == "stance":
        n = min(len(a), len(b))
        xa, xb = [v for _, v in a[:n]], [v for _, v in b[:n]]
    else:
        raise ValueError(f"pair_by must be 'subject' or 'stance', got {pair_by!r}")
    if len(xa) < 2:
        return len(xa), float("nan")
    return len(xa), float(stats.wilcoxon(xa, xb).pvalue)


def wilcoxon_variable_vs_constant(records: list[StanceFitRecord], joint: str, condition: str) -> tuple[int, float]:
    """Signed-rank test of Table 3 errors, variable vs constant model, paired by stance."""
    sel = [r.fit for r in records if r.joint == joint and r.condition == condition]
    if len(sel) < 2:
        return len(sel), float("nan")
    return len(sel), float(stats.wilcoxon([f.sse_variable for f in sel], [f.sse_constant for f in sel]).pvalue)


def markdown_table(header: list[str], rows: list[list[str]]) -> str:
    """A GitHub-flavoured Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines) + "\n"
