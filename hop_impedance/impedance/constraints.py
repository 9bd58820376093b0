"""The seed paper's constraints (Eqs. 7-9) as linear inequality rows.

At every sample l of the stance (all are linear in the coefficients, see
:mod:`hop_impedance.impedance.regression_model`):

- Eq. 7: K_l >= 0 and B_l >= 0;
- Eq. 8: E_s,l = int_t0^tl M_s d(rho) >= 0, with E_s0 = 0 at touchdown (choice:
  the spring cannot give back more energy than it received during this stance);
- Eq. 9: P_d,l = -M_d,l * omega_l <= 0, written as M_d,l * omega_l >= 0.

Each constraint is returned as a row ``a`` with ``a @ theta >= 0``. Rows that are
identically zero for the active terms (e.g. B >= 0 when no damping term is in
the model, or E_s at touchdown) are dropped; duplicate rows are kept (harmless).
"""

from __future__ import annotations

import numpy as np

from hop_impedance.impedance.regression_model import StanceRegressors

#: Names of the constraint families, in the order they are stacked.
CONSTRAINT_FAMILIES: tuple[str, ...] = (
    "stiffness_nonnegative",
    "damping_nonnegative",
    "spring_energy_nonnegative",
    "damper_power_nonpositive",
)


def stiffness_nonnegative_rows(regressors: StanceRegressors, columns: np.ndarray) -> np.ndarray:
    """Eq. 7, ``K_l >= 0`` at every sample: rows (N, p) of K (N m/rad) for the parameters ``columns``."""
    return regressors.stiffness_rows[:, columns]


def damping_nonnegative_rows(regressors: StanceRegressors, columns: np.ndarray) -> np.ndarray:
    """Eq. 7, ``B_l >= 0`` at every sample: rows (N, p) of B (N m s/rad) for the parameters ``columns``."""
    return regressors.damping_rows[:, columns]


def spring_energy_nonnegative_rows(regressors: StanceRegressors, columns: np.ndarray) -> np.ndarray:
    """Eq. 8, ``E_s,l = int_t0^tl M_s d(rho) >= 0`` (E_s0 = 0 at touchdown): rows (N, p) in J.

    (:func:`~hop_impedance.impedance.regression_model.spring_energy_polynomial_regressors`
    and its k3 column, integrated only when k3 is among ``columns``.)
    """
    return regressors.spring_energy_columns(columns)


def damper_power_nonpositive_rows(regressors: StanceRegressors, columns: np.ndarray) -> np.ndarray:
    """Eq. 9, ``P_d,l = -M_d,l omega_l <= 0`` written as ``M_d,l omega_l >= 0``: rows (N, p) in W."""
    return regressors.damper_power_columns(columns)


def constraint_rows(regressors: StanceRegressors, columns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stacked Eqs. 7-9 rows for the parameters ``columns`` (``A @ theta >= 0``).

    Parameters
    ----------
    regressors : StanceRegressors
        Rows of one stance.
    columns : ndarray of int, shape (p,)
        Indices into :data:`~hop_impedance.impedance.regression_model.PARAMETER_NAMES`
        of the parameters in the model (intercept first).

    Returns
    -------
    rows : ndarray, shape (m, p)
        One row per non-trivial constraint (units: N m/rad, N m s/rad, J, W),
        in :data:`CONSTRAINT_FAMILIES` order.
    family : ndarray of int, shape (m,)
        Index into :data:`CONSTRAINT_FAMILIES` of each row.
    """
    blocks = np.concatenate(
        (
            stiffness_nonnegative_rows(regressors, columns),
            damping_nonnegative_rows(regressors, columns),
            spring_energy_nonnegative_rows(regressors, columns),
            damper_power_nonpositive_rows(regressors, columns),
        )
    )
    keep = (blocks != 0.0).any(axis=1)
    family = np.repeat(np.arange(len(CONSTRAINT_FAMILIES)), regressors.n_samples)
    return blocks[keep], family[keep]


def constraint_violations(
    regressors: StanceRegressors, theta: np.ndarray, tolerance: float = 0.0
) -> dict[str, float]:
    """Worst violation of each constraint family for a full parameter vector.

    Parameters
    ----------
    regressors : StanceRegressors
    theta : ndarray, shape (9,)
        Full parameter vector in ``PARAMETER_NAMES`` order (zeros for dropped terms).
    tolerance : float
        Values above ``-tolerance`` count as satisfied.

    Returns
    -------
    dict
        Family name -> largest violation (>= 0; 0 when satisfied), in the
        family's unit (N m/rad, N m s/rad, J, W).
    """
    theta = np.asarray(theta, float)
    blocks = (
        regressors.stiffness_rows,
        regressors.damping_rows,
        regressors.spring_energy_rows,
        regressors.damper_power_rows,
    )
    out = {}
    for name, block in zip(CONSTRAINT_FAMILIES, blocks):
        values = block @ theta
        worst = float(max(0.0, -(values.min() + tolerance))) if values.size else 0.0
        out[name] = worst
    return out
