"""Constrained least squares of Eq. 6 under Eqs. 7-9, solved with OSQP.

Problem (one joint, one stance, p active parameters)::

    minimise   J = sum_l (tau_l - X_l theta)**2          (Eq. 6)
    subject to A theta >= 0                              (Eqs. 7-9)

Scaling: the columns of X differ by orders of magnitude (k2 multiplies rad^3,
b2 (rad/s)^3), so the QP is solved in ``theta_s = s * theta / |tau|`` with
``s`` the column norms of X, and each constraint row is normalised to unit
norm. OSQP then sees an objective of order 1 and unit-norm rows.

Working set (constraint generation, the fast path of :meth:`ConstrainedLeastSquares.solve`)
----------------------------------------------------------------------------------------
A has four rows per sample (K >= 0, B >= 0, E_s >= 0, P_d <= 0), ~300 rows
for 2-9 unknowns, and neighbouring samples give nearly identical rows. On the
full row set OSQP needs 1000-3000 ADMM iterations when constraints are active
and its polishing often fails on the near-duplicate rows. Instead:

1. start from the unconstrained optimum and an empty working set W;
2. solve the QP with only the rows in W with OSQP (warm-started, polished);
3. evaluate every row at that solution; for each run of consecutive violated
   rows add its most violated row to W; stop when no row is violated by more
   than OSQP's own feasibility tolerance ``eps_abs + eps_rel * max|A x|``.

The QP on W is a relaxation of the full QP, so its optimum, once feasible for
every row, is the optimum of the full QP (exact at convergence, up to the
tolerance above). With W empty this is the unconstrained least-squares
optimum itself: a convex QP whose unconstrained minimiser satisfies every
constraint has that minimiser as its optimum (KKT with all multipliers 0), so
it is returned without calling OSQP (``rounds = 0``, ``working_rows = 0``,
``iterations = 0``). OSQP solves every QP with a non-empty working set (it is
the solver of record for every fit where a constraint binds).

Degenerate working sets: a round's solve counts when OSQP's polishing succeeds and
every multiplier has the sign of an active bound (exact), and also when polishing
fails but ADMM converged at every stage down to ``eps`` (:data:`UNPOLISHED`): the
iterate is then the working-set QP's optimum to ``eps``, which is all the loop
needs, and step 3 still checks every row. Polishing fails where the optimum has
many nearly dependent active rows: on recordings/sim_2p20hz_hard's 5 ms live
window, stance 1's ankle (damping terms at 0) has 529 of its 1055 rows active
(session 32's recording; session 14's: stance 2's knee, 528 of 1051).
Before session 14 such a round sent the fit to the all-rows solve, which took
40,575 iterations (0.4 s, the live short-window p99) and ended 2.8e-7
infeasible with a KKT residual of 2.9e-4; kept on the working set it is
feasible to 1.3e-9 with a residual of 7e-11 (test_qp_fit.py,
``bench/qp_fallback.py``). A polished iterate with a wrong-sign multiplier
still goes to the all-rows solve (its active set was guessed wrong).

If W would exceed ``max_working_rows``, the loop exceeds
``max_rounds``, or a working-set solve does not converge, the full row set is
solved as before (:meth:`ConstrainedLeastSquares.solve_all_rows`), so a stance is rejected
only when OSQP fails on the full problem. Only OSQP status ``solved`` counts as
converged; anything else ("solved inaccurate", "maximum iterations reached",
...) is reported so the caller can reject the stance. ``theta = 0`` satisfies
every row, so the problem is never primal infeasible.

The exact path (:func:`exact_constrained_lstsq`, session 17)
-------------------------------------------------------------
The same problem solved exactly through NNLS (Lawson and Hanson's LSI -> LDP, ``scipy.optimize.nnls``), no
tolerance, no workspace. It is the solver of discovery's Eq. 7 option (``discovery.identify.EQ7_FIT``): there the
rows are K and B at every sample of up to 8 stances (726-2757 rows, 1-6 unknowns), zero-norm columns (hence
rank-deficient designs) occur, and the fit must keep the rows to ~1e-9. :class:`ConstrainedLeastSquares` does not
meet that: on 167 of those problems (every 20th of 3334 collected and compared by ``bench/eq7_solver_fold.py``,
session 17) 37 overflowed the 16-row working set to the full row set, which took up to 3.6
s (44 s in all, the exact path 0.63 s), left a row at -8.2e-4 (K or B, N m/rad or N m s/rad; the exact path's worst
-7.9e-9) and coefficients up to 0.20 (over max(1, |c|)) from the exact optimum; 14 had a zero-norm column, which
:func:`scaled_problem` refuses. On the seed's own problems (Eqs. 7-9 rows, 28 synthetic stances; the same
bench's seed-problems mode) the working set's objective is within 1.2e-12 (relative) of the exact one, the full-row path's
once 8.2e-5 above it; the exact path took 0.4-21 ms, the full-row path 1.8-397 ms. The seed keeps OSQP's
warm-started working set (its live path, its statuses and their tests); the exact solver is the reference
``test_qp_fit.py`` checks it against.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import osqp
from scipy import sparse
from scipy.linalg import lstsq
from scipy.optimize import nnls

#: OSQP's algebra backend. Named explicitly: without it every ``osqp.OSQP()``
#: tries to import the CUDA and MKL backends first (~1-2 ms per workspace).
OSQP_ALGEBRA = "builtin"
#: A working-set round whose ADMM iterate converged at every stage but whose polishing failed: kept
#: (module docstring, "Degenerate working sets").
UNPOLISHED = "solved, not polished"
#: OSQP's representation of an infinite bound.
OSQP_INFINITY = 1e30


@dataclass(frozen=True)
class QpSolution:
    """Result of one constrained fit.

    Attributes
    ----------
    coefficients : ndarray, shape (p,)
        Parameters in the caller's column order and units.
    status : str
        OSQP status text (``"solved"`` when converged).
    converged : bool
        True only for status ``"solved"``.
    sse : float
        Sum of squared residuals J (N^2 m^2).
    iterations : int
        ADMM iterations (summed over the working-set solves).
    polished : bool
        True when OSQP's polishing step succeeded (last solve).
    n_active : int
        Constraints active at the solution (scaled slack below 1e-7).
    working_rows : int
        Rows in the final working set; -1 when the full row set was solved,
        0 when the unconstrained optimum was feasible (no OSQP call).
    rounds : int
        OSQP solves on working sets (0 when only the full row set was solved
        or the unconstrained optimum was feasible).
    """

    coefficients: np.ndarray
    status: str
    converged: bool
    sse: float
    iterations: int
    polished: bool
    n_active: int
    working_rows: int = -1
    rounds: int = 0


def _upper_csc(matrix: np.ndarray) -> sparse.csc_matrix:
    """Upper triangle of a dense square matrix as CSC with a full, fixed pattern."""
    p = matrix.shape[0]
    rows, cols = np.triu_indices(p)
    order = np.lexsort((rows, cols))  # column-major
    rows, cols = rows[order], cols[order]
    indptr = np.concatenate([[0], np.cumsum(np.arange(1, p + 1))])
    return sparse.csc_matrix((matrix[rows, cols], rows, indptr), shape=(p, p))


@functools.cache
def _lower_triangle_indices(p: int) -> tuple[np.ndarray, np.ndarray]:
    """``np.tril_indices(p)``, built once per size."""
    return np.tril_indices(p)


def _upper_values(matrix: np.ndarray) -> np.ndarray:
    """Column-major upper-triangle values of a square matrix (data of :func:`_upper_csc`)."""
    values: np.ndarray = matrix.T[_lower_triangle_indices(matrix.shape[0])]
    return values


def _dense_csc(matrix: np.ndarray) -> sparse.csc_matrix:
    """Dense matrix as CSC keeping explicit zeros (fixed pattern for OSQP updates)."""
    m, p = matrix.shape
    indptr = np.arange(0, m * p + 1, m)
    indices = np.tile(np.arange(m), p)
    return sparse.csc_matrix((matrix.ravel(order="F"), indices, indptr), shape=(m, p))


def _unconstrained_optimum(P: np.ndarray, q: np.ndarray, Xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """Minimiser of the scaled objective without constraints, shape (p,).

    Normal equations ``P x = -q`` (P = Xs^T Xs has a unit diagonal); SVD
    least squares when P is numerically singular. Only the starting point of
    the working-set loop: OSQP computes the returned solution.
    """
    try:
        x: np.ndarray = np.linalg.solve(P, -q)
    except np.linalg.LinAlgError:
        return _least_squares(Xs, ys)
    return x if np.isfinite(x).all() else _least_squares(Xs, ys)


def _least_squares(Xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """SVD least-squares solution of ``Xs x = ys`` (``np.linalg.lstsq``), shape (p,)."""
    solution: np.ndarray = np.linalg.lstsq(Xs, ys, rcond=None)[0]
    return solution


def _most_violated_per_run(slack: np.ndarray, violated: np.ndarray) -> np.ndarray:
    """Index of the smallest slack in each run of consecutive violated rows, shape (runs,).

    Neighbouring samples give nearly identical rows, so one row per run is
    added at a time (adding whole runs makes the working set degenerate).
    """
    index = np.flatnonzero(violated).tolist()
    values = slack[violated].tolist()
    chosen, start = [], 0
    for end in range(1, len(index) + 1):  # a few dozen rows: plain Python beats numpy's per-call cost
        if end == len(index) or index[end] != index[end - 1] + 1:
            run = values[start:end]
            chosen.append(index[start + run.index(min(run))])  # first smallest, as np.argmin
            start = end
    return np.array(chosen, dtype=int)


def _shows_active_row(rows: np.ndarray, x: np.ndarray, y: np.ndarray) -> bool:
    """Whether OSQP's polish would find an active row at the ADMM iterate (x, y).

    OSQP's rule (polish.c ``form_Ared``) for a row with lower bound 0: lower
    active when ``z - l < -y``, with z ~ ``rows @ x``. Evaluated on the
    unscaled iterate OSQP returns, so it is a guard against the "no active
    set" print, not OSQP's own decision.
    """
    return bool((rows @ np.asarray(x, float) < -np.asarray(y, float)).any())


def least_squares_objective(design: np.ndarray, target: np.ndarray, theta: np.ndarray) -> float:
    """Eq. 6, ``J = sum_l (tau_l - X_l theta)**2`` (N^2 m^2): the sum of squared moment errors.

    Parameters
    ----------
    design : ndarray, shape (N, p)
        Regressor rows X of the model's parameters (N m per coefficient unit).
    target : ndarray, shape (N,)
        Measured moment tau (N m).
    theta : ndarray, shape (p,)
        Parameters (NaN in any gives NaN).
    """
    if not np.isfinite(theta).all():
        return float("nan")
    residual = target - design @ theta
    return float(residual @ residual)


def exact_constrained_lstsq(design: np.ndarray, target: np.ndarray, constraints: np.ndarray) -> np.ndarray:
    """``argmin |target - design @ theta|^2`` subject to ``constraints @ theta >= 0``, exactly, through NNLS.

    Lawson and Hanson's LSI -> LDP: with the thin SVD ``design = U S V^T`` (rank r; ``theta = V_r w``, the
    minimum-norm reading of a rank-deficient design), ``z = S_r w - U_r^T target`` turns the problem into the
    least-distance program ``min |z|`` subject to ``G z >= h``, ``G = constraints V_r S_r^-1`` (rows scaled to unit
    norm, rows that vanish on the range dropped), ``h = -G U_r^T target``, whose solution is ``z = -r[:r] / r[r]``
    with ``r = E u - e`` and ``u = nnls(E = [G^T; h^T], e = (0, ..., 0, 1))``. ``theta = 0`` is feasible, so the
    program always has a solution. Polish: NNLS leaves the active rows at ~1e-9 of the coefficients' scale; the
    least squares on the null space of the rows NNLS used (``u > 0``) hits them exactly and is kept when it keeps
    every row and fits as well (a wrong active set would give a feasible but worse fit). Zero-norm columns get 0.
    (Module docstring, "The exact path".)

    Parameters
    ----------
    design : ndarray, shape (N, p)
    target : ndarray, shape (N,)
    constraints : ndarray, shape (m, p)

    Returns
    -------
    ndarray, shape (p,)
    """
    x, y, rows = np.asarray(design, float), np.asarray(target, float), np.asarray(constraints, float)
    u_mat, sv, vt = np.linalg.svd(x, full_matrices=False)
    keep = sv > sv[0] * max(x.shape) * np.finfo(float).eps
    u_mat, sv, v = u_mat[:, keep], sv[keep], vt[keep].T
    d = u_mat.T @ y
    g = (rows @ v) / sv
    norms = np.linalg.norm(g, axis=1)
    g, r_use = g[norms > 0], norms[norms > 0]
    g = g / r_use[:, None]
    h = -g @ d
    e_mat = np.vstack([g.T, h[None, :]])
    unit = np.zeros(len(sv) + 1)
    unit[-1] = 1.0
    u, _ = nnls(e_mat, unit, maxiter=50 * e_mat.shape[1])
    r = e_mat @ u - unit
    z = -r[:-1] / r[-1]
    theta: np.ndarray = v @ ((z + d) / sv)
    active = rows[norms > 0][u > 0]
    if active.size:
        _, sa, vta = np.linalg.svd(active)
        null = vta[int(np.sum(sa > sa[0] * max(active.shape) * np.finfo(float).eps)):].T
        if null.shape[1]:
            polished = null @ lstsq(x @ null, y, lapack_driver="gelsy")[0]
            scale = np.abs(rows) @ np.abs(polished)
            as_good = np.sum((y - x @ polished) ** 2) <= np.sum((y - x @ theta) ** 2) * (1 + 1e-6) + 1e-12
            if as_good and np.all(rows @ polished >= -1e-12 * np.maximum(scale, 1.0)):
                theta = polished
    return theta


@dataclass(frozen=True)
class ScaledProblem:
    """Eq. 6 under Eqs. 7-9 as OSQP solves it: ``min 1/2 x^T P x + q^T x`` s.t. ``A x >= 0``.

    With ``theta = x * target_norm / column_norms`` this is Eq. 6 divided by
    ``|tau|^2 / 2`` (unit-norm columns and target), and A's rows are the
    constraint rows in x, each scaled to unit norm.

    Attributes
    ----------
    design : ndarray, shape (N, p)
        X in the caller's units.
    target : ndarray, shape (N,)
        tau (N m).
    scaled_design, scaled_target : ndarray, shapes (N, p) and (N,)
        ``X / column_norms`` and ``tau / target_norm``.
    P, q : ndarray, shapes (p, p) and (p,)
        ``Xs^T Xs`` and ``-Xs^T ys``.
    A : ndarray, shape (m, p)
        Unit-norm constraint rows in x.
    column_norms : ndarray, shape (p,)
    target_norm : float
    """

    design: np.ndarray
    target: np.ndarray
    scaled_design: np.ndarray
    scaled_target: np.ndarray
    P: np.ndarray
    q: np.ndarray
    A: np.ndarray
    column_norms: np.ndarray
    target_norm: float

    def unscaled(self, x: np.ndarray) -> np.ndarray:
        """theta (caller's units) of a scaled solution x."""
        theta: np.ndarray = x * self.target_norm / self.column_norms
        return theta


def scaled_problem(design: np.ndarray, target: np.ndarray, constraints: np.ndarray) -> ScaledProblem:
    """Eq. 6 (objective) and Eqs. 7-9 (``constraints @ theta >= 0``) scaled for OSQP (module docstring, "Scaling").

    Raises
    ------
    ValueError
        When a regressor column or the moment is zero (nothing to scale by).
    """
    X = np.asarray(design, float)
    y = np.asarray(target, float)
    col_norm = np.sqrt(np.einsum("ij,ij->j", X, X))
    y_norm = float(np.sqrt(y @ y))
    if (col_norm == 0.0).any() or y_norm == 0.0:
        raise ValueError("constrained fit needs non-zero regressor columns and a non-zero moment")
    Xs = X / col_norm
    ys = y / y_norm
    A = np.asarray(constraints, float).reshape(-1, X.shape[1]) / col_norm
    row_norm = np.sqrt(np.einsum("ij,ij->i", A, A))
    A = A / np.where(row_norm > 0.0, row_norm, 1.0)[:, None]
    return ScaledProblem(X, y, Xs, ys, Xs.T @ Xs, -(Xs.T @ ys), A, col_norm, y_norm)


class ConstrainedLeastSquares:
    """Reusable OSQP solver for Eq. 6 under ``A theta >= 0``.

    Keep one instance per joint: OSQP workspaces are kept per problem size
    and updated instead of rebuilt, and solves are warm-started.

    Parameters
    ----------
    eps : float
        OSQP ``eps_abs`` and ``eps_rel`` on the scaled problem (also the
        feasibility tolerance of the working-set check).
    max_iter : int
        OSQP iteration limit per solve; reaching it is reported as not converged.
    coarse_eps, middle_eps : float
        Tolerances of the first two ADMM stages. Each stage's iterate is
        polished (exact active-set solution) when it shows an active row and
        accepted when the polish succeeds; otherwise ADMM continues, warm, to
        the next stage and finally to ``eps``. Result-neutral (a successful
        polish is the exact optimum whichever stage it comes from); the middle
        stage exists for speed: where the coarse iterate has not yet
        identified the active set, two orders of magnitude later it usually
        has, instead of ADMM running on to ``eps`` (docs/impedance_model.md,
        "Speed", ``bench_impedance_fit.py --slowest``).
    working_set : bool
        Use the working-set path (module docstring); False always solves the
        full row set.
    max_working_rows : int
        Working-set capacity (rows); more rows fall back to the full set.
    max_rounds : int
        Working-set solves before falling back to the full set.
    """

    def __init__(
        self,
        eps: float = 1e-9,
        max_iter: int = 20000,
        coarse_eps: float = 1e-5,
        middle_eps: float = 1e-7,
        working_set: bool = True,
        max_working_rows: int = 16,
        max_rounds: int = 12,
    ) -> None:
        self.eps = eps
        self.coarse_eps = coarse_eps
        #: ADMM tolerances of the successive stages (see the class docstring).
        self.stages = tuple(e for e in (coarse_eps, middle_eps) if e > eps) + (eps,)
        self.working_set = working_set
        self.max_working_rows = max_working_rows
        self.max_rounds = max_rounds
        self.settings = dict(
            eps_abs=eps,
            eps_rel=eps,
            max_iter=max_iter,
            polish_refine_iter=5,
            verbose=False,
        )
        self._solver: osqp.OSQP | None = None
        self._shape: tuple[int, int] | None = None
        self._last_x: dict[int, np.ndarray] = {}
        self._small: dict[int, osqp.OSQP] = {}
        self._small_settings: dict[int, tuple[bool, float]] = {}
        #: The last :class:`QpSolution` returned (diagnostics and benchmarks).
        self.last_solution: QpSolution | None = None

    def _result(
        self, problem: ScaledProblem, xs: np.ndarray, status: str, info: dict[str, Any], slack: np.ndarray | None = None
    ) -> QpSolution:
        """The :class:`QpSolution` of the scaled solution ``xs`` (``slack = A @ xs`` when already known).

        ``info``: ``iterations``, ``polished``, ``working_rows``, ``rounds`` (as in :class:`QpSolution`).
        """
        converged = status == "solved" and bool(np.isfinite(xs).all())
        theta = problem.unscaled(xs)
        A = problem.A
        if slack is None:
            slack = A @ xs if A.shape[0] else np.zeros(0)
        self.last_solution = QpSolution(
            coefficients=theta,
            status=status,
            converged=bool(converged),
            sse=least_squares_objective(problem.design, problem.target, theta),
            iterations=int(info["iterations"]),
            polished=bool(info["polished"]),
            n_active=int((slack < 1e-7).sum()) if converged else 0,
            working_rows=info["working_rows"],
            rounds=info["rounds"],
        )
        return self.last_solution

    # -- public solves ---------------------------------------------------
    def solve(self, design: np.ndarray, target: np.ndarray, constraints: np.ndarray) -> QpSolution:
        """Minimise ``|target - design @ theta|^2`` subject to ``constraints @ theta >= 0``.

        Working-set path (module docstring) with fallback to :meth:`solve_all_rows`.

        Parameters
        ----------
        design : ndarray, shape (N, p)
            Regressor matrix X (columns with zero norm are not allowed).
        target : ndarray, shape (N,)
            Measured moment tau (N m).
        constraints : ndarray, shape (m, p)
            Rows a with ``a @ theta >= 0``; m may be 0.

        Returns
        -------
        QpSolution
        """
        if not self.working_set:
            return self.solve_all_rows(design, target, constraints)
        problem = scaled_problem(design, target, constraints)
        P, q, A = problem.P, problem.q, problem.A
        p = q.size
        x = _unconstrained_optimum(P, q, problem.scaled_design, problem.scaled_target)
        work = np.zeros(0, dtype=int)
        duals = np.zeros(0)
        iterations, rounds, polished = 0, 0, False
        solver: osqp.OSQP | None = None  # OSQP workspace and P data, fetched at the first round only
        P_upper = np.zeros(0)
        while True:
            slack = A @ x
            tol = self.eps + self.eps * (float(np.abs(slack).max()) if slack.size else 0.0)
            violated = slack < -tol
            if work.size:
                violated[work] = False
            if not violated.any():  # W's optimum is feasible: it is the full QP's optimum
                info = {"iterations": iterations, "polished": polished, "working_rows": work.size, "rounds": rounds}
                return self._result(problem, x, "solved", info, slack=slack)
            work = np.concatenate((work, _most_violated_per_run(slack, violated)))
            if work.size > self.max_working_rows or rounds >= self.max_rounds:
                break
            if solver is None:
                solver, P_upper = self._small_solver(p), _upper_values(P)
            status, x_new, duals, iters, polished = self._solve_rows(solver, P_upper, q, A[work], x, duals)
            iterations += iters
            rounds += 1
            if status not in ("solved", UNPOLISHED) or not np.isfinite(x_new).all():
                break
            x = x_new
        return self.solve_all_rows(design, target, constraints)

    def prepare(self, p: int) -> None:
        """Set up the working-set workspace for ``p`` unknowns now instead of at the first violated constraint.

        OSQP's set-up is most of a process's first constrained fit's extra cost (a live
        estimator's first stance, issue 15); a stance whose unconstrained optimum is
        feasible never reaches it, so a warm-up fit alone does not pay it.
        """
        if self.working_set:
            self._small_solver(p)

    def _small_solver(self, p: int) -> osqp.OSQP:
        """OSQP workspace for p unknowns and ``max_working_rows`` rows (dense pattern), cached per p."""
        solver = self._small.get(p)
        if solver is None:
            m = self.max_working_rows
            solver = osqp.OSQP(algebra=OSQP_ALGEBRA)
            solver.setup(
                _upper_csc(np.eye(p)),
                np.zeros(p),
                _dense_csc(np.ones((m, p))),
                np.full(m, -OSQP_INFINITY),
                np.full(m, OSQP_INFINITY),
                **{**self.settings, "polishing": True},
            )
            self._small[p] = solver
            self._small_settings[p] = (True, self.eps)
        return solver

    def _set(self, p: int, polishing: bool, eps: float) -> None:
        """Change polishing and eps_abs = eps_rel of a working-set workspace only when they differ.

        (``OSQP.update_settings`` walks every setting in Python; skipping
        no-op calls saves a noticeable share of a sub-millisecond solve.)
        """
        if self._small_settings[p] != (polishing, eps):
            self._small[p].update_settings(polishing=polishing, eps_abs=eps, eps_rel=eps)
            self._small_settings[p] = (polishing, eps)

    def _solve_rows(
        self, solver: osqp.OSQP, P_upper: np.ndarray, q: np.ndarray, rows: np.ndarray, x0: np.ndarray, y0: np.ndarray
    ) -> tuple[str, np.ndarray, np.ndarray, int, bool]:
        """One OSQP solve of the scaled QP with ``rows @ x >= 0`` (padded with free rows).

        The stages of :meth:`_solve_in_stages`; a polished iterate is accepted
        when every multiplier has the sign of an active lower bound
        (:meth:`_right_signs`). The working set is never empty here (its first
        rows are violated by the unconstrained optimum), so its exact optimum
        always has an active row.

        Returns
        -------
        status : str
            ``"solved"`` only for an exact (polished, sign-checked) solution.
        x : ndarray, shape (p,)
        y : ndarray, shape (k,)
            OSQP multipliers of the working rows (warm start of the next round).
        iterations : int
        polished : bool
        """
        m, p, k = self.max_working_rows, q.size, rows.shape[0]
        A = np.zeros((m, p))
        A[:k] = rows
        lower = np.full(m, -OSQP_INFINITY)
        lower[:k] = 0.0
        solver.update(Px=P_upper, q=q, Ax=A.ravel(order="F"), l=lower)
        y_start = np.zeros(m)
        y_start[: y0.size] = y0
        solver.warm_start(x=x0, y=y_start)
        result, iterations, exact, polished = self._solve_in_stages(
            solver, lambda polishing, eps: self._set(p, polishing=polishing, eps=eps), rows, k,
            exact=lambda polished_result: self._right_signs(np.asarray(polished_result.y, float)[:k]),
        )
        status = str(result.info.status)
        if not exact and status == "solved":  # the caller keeps UNPOLISHED; wrong signs send it to the full row set
            status = UNPOLISHED if not polished else "solved with wrong-sign multipliers"
        return status, np.asarray(result.x, float), np.asarray(result.y, float)[:k], iterations, polished

    def solve_all_rows(self, design: np.ndarray, target: np.ndarray, constraints: np.ndarray) -> QpSolution:
        """The same QP with every constraint row given to OSQP (reference and fallback path).

        Parameters and return as :meth:`solve`.
        """
        problem = scaled_problem(design, target, constraints)
        P, q, A = problem.P, problem.q, problem.A
        p = q.size
        if A.shape[0] == 0:
            A = np.zeros((1, p))  # keep OSQP's interface: one void row 0 <= 0 <= inf
        lower = np.zeros(A.shape[0])
        upper = np.full(A.shape[0], np.inf)

        # The unconstrained optimum: if it is feasible it is the QP optimum
        # (KKT with zero multipliers); OSQP then only confirms it and polishing
        # (which needs an active set) is switched off.
        x_ols = np.linalg.lstsq(problem.scaled_design, problem.scaled_target, rcond=None)[0]
        ols_feasible = bool((A @ x_ols >= -1e-9).all())
        P_csc, A_csc = _upper_csc(P), _dense_csc(A)
        shape = (p, A.shape[0])
        solver = self._solver
        if solver is not None and self._shape == shape:
            solver.update(Px=P_csc.data, q=q, Ax=A_csc.data, l=lower, u=upper)
        else:
            solver = self._solver = osqp.OSQP(algebra=OSQP_ALGEBRA)
            solver.setup(P_csc, q, A_csc, lower, upper, **{**self.settings, "polishing": False})
            self._shape = shape
        if ols_feasible or p not in self._last_x:
            solver.warm_start(x=x_ols)
        else:
            solver.warm_start(x=self._last_x[p])
        result, iterations, _, _ = self._solve_in_stages(
            solver,
            lambda polishing, eps: solver.update_settings(eps_abs=eps, eps_rel=eps, polishing=polishing),
            A, A.shape[0], exact=lambda polished_result: True, accept_unpolished=ols_feasible,
        )
        status = str(result.info.status)
        xs = np.asarray(result.x, float)
        if status == "solved" and np.isfinite(xs).all():
            self._last_x[p] = xs.copy()
        info = {"iterations": iterations, "polished": int(result.info.status_polish) == 1, "working_rows": -1, "rounds": 0}
        return self._result(replace(problem, A=A), xs, status, info)

    def _right_signs(self, duals: np.ndarray) -> bool:
        """Every working-row multiplier has the sign of an active lower bound (OSQP's y <= 0, to ``eps``).

        A positive y means a wrongly guessed active row: a feasible but not optimal point.
        """
        return not (duals > self.eps * max(1.0, float(np.abs(duals).max(initial=0.0)))).any()

    def _solve_in_stages(
        self,
        solver: osqp.OSQP,
        configure: Callable[[bool, float], None],
        rows: np.ndarray,
        k: int,
        exact: Callable[[Any], bool],
        accept_unpolished: bool = False,
    ) -> tuple[Any, int, bool, bool]:
        """ADMM through :attr:`stages`; polish a stage's iterate only once it shows an active row.

        Shared by the working-set and the full-row paths. Each stage runs ADMM
        (warm, from the previous stage's iterate) without polishing. When its
        iterate shows an active row by OSQP's own rule
        (:func:`_shows_active_row`), the iterate is polished: polishing
        without one makes OSQP 1.1 print "Polishing not needed ..." on stdout
        from C, whatever ``verbose`` says, which would corrupt
        ``analyze --json -``. The polishing re-solve runs at ``coarse_eps``: the
        iterate has converged, so ADMM stops at its first check and OSQP
        polishes (at the stage's own tolerance a warm re-solve once took
        20,000 iterations). A successful polish that passes ``exact`` ends the
        stages; so does the first solved stage when ``accept_unpolished``.

        Parameters
        ----------
        solver : osqp.OSQP
            Workspace, already set up and warm-started.
        configure : callable
            ``configure(polishing, eps)`` sets OSQP's polishing and eps_abs = eps_rel.
        rows : ndarray, shape (k, p)
            Scaled constraint rows (lower bound 0), OSQP's first ``k = len(rows)`` rows.
        exact : callable
            ``exact(result) -> bool`` for a solved, polished result (the multiplier sign check).
        accept_unpolished : bool
            Accept the first solved stage as it is (a feasible unconstrained optimum: nothing to polish).

        Returns
        -------
        (result, iterations, exact, polished): OSQP's last result, ADMM
        iterations of all solves, whether it was accepted as exact, and
        whether the last polishing attempt succeeded.
        """
        result, iterations, polished = None, 0, False
        for eps in self.stages:
            configure(False, eps)
            result = solver.solve(raise_error=False)
            iterations += int(result.info.iter)
            if str(result.info.status) != "solved":
                continue
            if accept_unpolished:
                return result, iterations, True, polished
            if not _shows_active_row(rows, result.x, result.y[:k]):
                continue
            configure(True, self.coarse_eps)
            result = solver.solve(raise_error=False)
            iterations += int(result.info.iter)
            polished = int(result.info.status_polish) == 1
            if str(result.info.status) == "solved" and polished and exact(result):
                return result, iterations, True, polished
        return result, iterations, False, polished
