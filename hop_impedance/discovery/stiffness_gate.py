"""The current model's joint stiffness through the simulation: a gate before an effect is named (issue 16).

Why
---
Every model is identified by regression on the inverse-dynamics moments. Where a joint barely moves the
regression cannot pin its stiffness: on the second generator's strict null seed 3 the hip moves 0.04-0.17
rad in stance and, with the generator's own segment parameters given to the analysis, the baseline's hip
k0 comes out at 94 N m/rad against the true 138, its in-sample forward gap at 0.0345 against the true law's
0.0194 (``bench/discovery_strict_floor.py --seeds 3``). That error is not an effect, but a flexible
candidate (an angle- or rate-dependent stiffness, an activation, damping), identified by the same
regression, shrank the held-out gap significantly through its extra coefficients: 8 of 60 strict nulls
were named falsely with the body split absorbed, and with the generator's own body 4 of those 8 still were
(``bench/discovery_strict_floor.py --discover`` repeats that; measured before the gate).

Rule
----
Only when some candidate passed the held-out test: the current model's constant stiffness ``k0`` (one
factor per joint on the regression's values, everything else kept) is chosen by the simulation,
minimising the mean forward gap of every stance simulated from its measured touchdown state (``M_td``
re-estimated per stance for each ``k0``): Nelder-Mead on the log factors (bounded to
:data:`LOG_FACTOR_BOUND`, at most :data:`NM_MAX_EVALUATIONS` evaluations of all stances; the search is
:data:`SEARCH`, see "Search" below). The same is done for the passing candidate
(identified on all stances, its own coefficients kept, its ``k0`` shot the same way), and it is named
only if it beats the shot current model: the same one-sided t-test on the per-stance log gap ratios
(Bonferroni over the round's candidates) and the same relevance floor
(:data:`hop_impedance.discovery.forward_selection.MIN_SHRINK`). In words: an effect is named only if,
with the stiffness each model can reach through the simulation, the effect still makes the model
significantly better forward. Candidates are tried in the order of their held-out mean log ratio; the
first that passes is named.

Why both are shot: shooting only the current model is unfair to a true effect. On the outside
generator's angle-dependent file (``angle_dependent_stiffness_1201``) the shot constant stiffness reached
an in-sample gap of 0.018, below the regression-identified angle law's held-out 0.034 (the true law's
gap there is 0.0089), and the effect was lost.

Choices: both models are shot in-sample (all stances), so this is a comparison of what each model
structure can reach, after the held-out test has shown the candidate generalises. Only ``k0`` is shot:
it is the parameter every model shares, and three parameters keep a search within 20 evaluations of
all stances (reported in ``timing.stiffness_s`` and ``evaluations``). A candidate's search starts from the
current model's factors when they beat its regression's k0; the candidate named in one round is the next
round's current model, and its search is reused (``workflow._gated``).

Search (session 9, issue 16's < 60 s): the gap is a sum of squares (:func:`hop_impedance.discovery.
forward_selection._gap_of`), so ``method="levenberg-marquardt"`` (:func:`_levenberg_marquardt`: a
forward-difference Jacobian, three points of all stances per iteration in one pool map, at most
:data:`LM_MAX_EVALUATIONS` evaluations) converges further in fewer simulations than Nelder-Mead (simplex
step 0.5, <= 20 evaluations). On the bench recording (``bench/bench_discovery.py --search
levenberg-marquardt``) the whole run took 56.3 s (load 0.7-1.3) with searches of 13-14 evaluations. It
is NOT the default, because the better search changes what is named: on the outside angle file
``angle_dependent_stiffness_1201`` it brings the constant-stiffness model's in-sample gap to 0.0082
(Nelder-Mead 0.018, the true angle law's 0.0089), the angle law's shot gap to 0.0057, and the gate's
p-value to 0.056 (threshold 0.05/8), so the true effect is no longer named (``hop-impedance discover`` on
that file at commit b1e23a7, where it was the default; a scratch run with 30 evaluations and a 1 % stop:
0.0082 vs 0.0045, p = 0.0075, still not named). With Nelder-Mead the file is named because that
search stops short for the constant model: the gate's outcome there depends on the search's budget,
which is for the lead to decide (docs/discovery.md,
Runtime).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery.body_nuisance import FAILED_GAP
from hop_impedance.discovery.model import ModelSpec, feature_names

#: Largest |log factor| on a joint's regression k0 (a factor of e^1.5 = 4.5 either way).
LOG_FACTOR_BOUND = 1.5
#: The search: ``"nelder-mead"`` (session 8's; the default, it keeps the names, see the module docstring) or
#: ``"levenberg-marquardt"`` (session 9: faster and better converged, and it loses the outside angle file).
SEARCH = "nelder-mead"
#: Search budgets: evaluations of all stances (start, simplex, Jacobian and trial points each count one).
NM_MAX_EVALUATIONS = 20
LM_MAX_EVALUATIONS = 14
#: Nelder-Mead (also Levenberg-Marquardt's fallback when a stance fails at the start): first simplex step.
INITIAL_STEP = 0.5
#: Levenberg-Marquardt: forward-difference step on the log factors, first damping (share of diag J'J),
#: stop when a step moves every log factor by less than STEP_TOL or shrinks the mean gap by less than GAP_TOL.
FD_STEP = 0.03
LM_DAMPING = 1e-2
STEP_TOL = 0.02
GAP_TOL = 0.05


@dataclass(frozen=True)
class ShotStiffness:
    """The current model with its k0 chosen by the simulation."""

    factors: np.ndarray
    k0_regression: np.ndarray
    gaps: np.ndarray
    gap_regression: float
    evaluations: int
    seconds: float
    method: str = "levenberg-marquardt"

    def as_json(self) -> dict:
        return {"k0_regression_nm_per_rad": np.round(self.k0_regression, 2).tolist(),
                "k0_shot_nm_per_rad": np.round(self.k0_regression * self.factors, 2).tolist(),
                "in_sample_gap_regression_shot": [round(self.gap_regression, 5), round(float(np.mean(self.gaps)), 5)],
                "per_stance_gap_shot": np.round(self.gaps, 5).tolist(),
                "evaluations": self.evaluations, "seconds": round(self.seconds, 2), "method": self.method}


@dataclass(frozen=True)
class _Point:
    """All stances simulated at one set of log factors ``x``."""

    x: np.ndarray
    runs: list

    @property
    def gaps(self) -> np.ndarray:
        return np.array([r["gap"] for r in self.runs])

    @property
    def mean_gap(self) -> float:
        return float(np.mean(np.minimum(self.gaps, FAILED_GAP)))


class _Search:
    """Evaluations of one model's stances at log factors on its regression k0 (each point simulated once)."""

    def __init__(self, ev: fs.HeldOutEvaluator, spec_fit: ModelSpec, coefs: np.ndarray):
        self.ev, self.spec, self.coefs = ev, spec_fit, np.array(coefs, float)
        self.col = feature_names(spec_fit).index("k0")
        self.seen: dict[tuple, _Point] = {}

    def points(self, xs: list[np.ndarray]) -> list[_Point]:
        """Every stance at each of ``xs`` (clipped to the bound); the new ones in one pool map."""
        xs = [np.clip(x, -LOG_FACTOR_BOUND, LOG_FACTOR_BOUND) for x in xs]
        new = list({tuple(np.round(x, 6)): x for x in xs if tuple(np.round(x, 6)) not in self.seen}.items())
        runs = self.ev.stance_residuals(self.spec, [self._coefs(x) for _, x in new]) if new else []
        for (key, x), r in zip(new, runs):
            self.seen[key] = _Point(x, r)
        return [self.seen[tuple(np.round(x, 6))] for x in xs]

    def _coefs(self, x: np.ndarray) -> np.ndarray:
        c = self.coefs.copy()
        c[:, self.col] *= np.exp(x)
        return c


def shoot_stiffness(ev: fs.HeldOutEvaluator, spec_fit: ModelSpec, coefs: np.ndarray,
                    start: ShotStiffness | None = None, method: str | None = None) -> ShotStiffness:
    """``spec_fit`` (identified on all stances, coefficients ``coefs``) with its k0 chosen by the simulation.

    ``start``: the current model's result; its factors are the search's start when they beat the
    regression's k0 (a candidate that leaves k0's meaning unchanged, e.g. an offset, needs the same factors).
    ``method``: :data:`SEARCH` by default; Levenberg-Marquardt on the per-sample residuals
    (:func:`_levenberg_marquardt`) falls back to Nelder-Mead on the mean gap when a stance fails to simulate at
    the start (no residuals to linearise).
    """
    t0 = time.perf_counter()
    search = _Search(ev, spec_fit, coefs)
    starts = [np.zeros(3)] + ([np.log(start.factors)] if start is not None else [])
    regression, *other = search.points(starts)
    x0 = other[0] if other and other[0].mean_gap < regression.mean_gap else regression
    if (method or SEARCH) == "levenberg-marquardt" and not _failed(x0):
        best, method = _levenberg_marquardt(search, x0), "levenberg-marquardt"
    else:
        best, method = _nelder_mead(search, x0), "nelder-mead"
    return ShotStiffness(np.exp(best.x), search.coefs[:, search.col], best.gaps, regression.mean_gap,
                         len(search.seen), time.perf_counter() - t0, method)


def _nelder_mead(search: _Search, x0: _Point) -> _Point:
    """The best point of a Nelder-Mead search on the mean gap from ``x0`` (within the budget)."""
    def mean_gap(x: np.ndarray) -> float:
        return search.points([x])[0].mean_gap

    simplex = np.vstack([x0.x, x0.x + INITIAL_STEP * np.eye(3)])
    res = minimize(mean_gap, x0.x, method="Nelder-Mead",
                   options={"initial_simplex": simplex, "maxfev": NM_MAX_EVALUATIONS, "xatol": STEP_TOL, "fatol": 1e-5})
    best = search.points([res.x])[0]
    return best if best.mean_gap < x0.mean_gap else x0


def _levenberg_marquardt(search: _Search, x0: _Point) -> _Point:
    """Levenberg-Marquardt from ``x0`` on the stances' scaled residuals (their sum of squares is the mean gap).

    Each iteration: a forward-difference Jacobian at the best point (:data:`FD_STEP`, the three columns in
    one pool map), then trial steps until the mean gap falls (the damping grows after each that does not).
    Stops when a step moves every log factor less than :data:`STEP_TOL`, gains less than :data:`GAP_TOL`,
    or at the budget; the best point found is returned. (Broyden's rank-one update instead of a new
    Jacobian was tried: on the bench recording's baseline it needed 18 evaluations for the gap LM reaches in
    13, the hip's factor is poorly determined and the updated Jacobian lost it.)
    """
    best, damping = x0, LM_DAMPING
    while len(search.seen) + 4 <= LM_MAX_EVALUATIONS:
        lin = _differenced(search, best)
        if lin is None:
            break
        a, g = lin.jac.T @ lin.jac, lin.jac.T @ lin.vec(best)
        while len(search.seen) < LM_MAX_EVALUATIONS:
            step = -np.linalg.solve(a + damping * np.diag(np.diag(a) + 1e-12 * np.trace(a)), g)
            x = np.clip(best.x + step, -LOG_FACTOR_BOUND, LOG_FACTOR_BOUND)
            if np.max(np.abs(x - best.x)) < STEP_TOL:
                return best
            trial = search.points([x])[0]
            if trial.mean_gap < best.mean_gap:
                small = trial.mean_gap > (1.0 - GAP_TOL) * best.mean_gap
                best, damping = trial, damping / 3.0
                if small:
                    return best
                break
            damping *= 4.0
        else:
            break
    return best


def _differenced(search: _Search, best: _Point) -> _Linearisation | None:
    """The Jacobian by forward differences at ``best`` (None if a stance fails to simulate there)."""
    h = np.where(best.x + FD_STEP > LOG_FACTOR_BOUND, -FD_STEP, FD_STEP)
    cols = search.points([best.x + h[k] * np.eye(3)[k] for k in range(3)])
    return None if any(_failed(c) for c in cols) else _Linearisation(best, cols, h)


def _failed(p: _Point) -> bool:
    return any(r["samples"] is None for r in p.runs)


class _Linearisation:
    """Residual vector and its Jacobian in the log factors, over the samples every run compared has.

    A run that takes off earlier has fewer samples; each stance is compared over the shortest of the runs,
    weighted by ``1/sqrt(n)`` of the start's run so that the squares sum to about 10 x the mean gap.
    """

    def __init__(self, base: _Point, cols: list[_Point], h: np.ndarray):
        self.m = [min(len(p.runs[i]["samples"]) for p in [base, *cols]) for i in range(len(base.runs))]
        self.w = [1.0 / np.sqrt(len(r["samples"])) for r in base.runs]
        r = self.vec(base)
        self.jac = np.stack([(self.vec(c) - r) / hk for c, hk in zip(cols, h)], axis=1)

    def vec(self, p: _Point) -> np.ndarray:
        return np.concatenate([np.r_[w * run["samples"][:m].ravel(), run["terms"]]
                               for run, m, w in zip(p.runs, self.m, self.w)])


def gate(cand: ShotStiffness, current: ShotStiffness, n_candidates: int) -> dict:
    """Does the candidate beat the current model, both with k0 chosen through the simulation (module docstring)?"""
    d, shrink, p = fs.compare_gaps(current.gaps, cand.gaps)
    return {"passes": fs.significant(p, shrink, n_candidates), "p_value": p,
            "shrink_against_shot": shrink, "per_stance_log_gap_ratio": np.round(d, 4).tolist(), **cand.as_json()}
