"""Regressors of the seed paper's joint impedance model (Eqs. 3-5).

Model (one joint, one stance; seed paper Eq. 3)
-----------------------------------------------
With ``d = rho - rho0`` and ``w = omega - omega0`` (rho0, omega0 = first sample
of the stance, i.e. touchdown)::

    K(rho, omega) = k0 + k1 d + k2 d**2 + k3 w              (stiffness, N m/rad)
    B(rho, omega) = b0 + b1 w + b2 w**2 + b3 d              (damping, N m s/rad)

Integrated along the measured trajectory (Eq. 4)::

    M_s = M_s0 + int K d(rho)
        = m0 + k0 d + k1 d**2/2 + k2 d**3/3 + k3 int_t0^t w omega dt
    M_d = M_d0 + int B d(omega)
        = b0 omega + b1 w**2/2 + b2 w**3/3 + b3 int d d(omega)

and the joint moment is ``M = M_s + M_d`` (Eq. 5), extensor positive, rho
increasing with flexion (``hop_impedance.biomech.joint_angles``).

Touchdown moment (a choice, see ``docs/impedance_model.md``)
------------------------------------------------------------
The touchdown moment ``M0 = M_s0 + M_d0`` is a free intercept. It is split as
``M_d0 = b0 * omega0`` (at touchdown the damper acts as a linear viscous damper
with the touchdown damping B = b0) and ``M_s0 = m0`` (the rest). The split only
matters for the energy constraints (Eqs. 8-9): the column space of the
regression, hence every fitted k and b, is the same for any split, because
``b0 * omega = b0 * omega0 + b0 * w`` and the constant part is absorbed by m0.

Path integrals
--------------
``int w omega dt`` (k3 term) is path dependent and integrated numerically with
``scipy.integrate.cumulative_simpson``. The b3 term is integrated by parts,
``int_t0^t d d(omega) = d w - int_t0^t w omega dt`` (``d(t0) = 0``), so it needs
no second derivative of the angle.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
from scipy.integrate import cumulative_simpson

#: The eight coefficients of Eq. 3, in the order of every coefficient vector.
TERM_NAMES: tuple[str, ...] = ("k0", "k1", "k2", "k3", "b0", "b1", "b2", "b3")
STIFFNESS_TERMS: tuple[str, ...] = ("k0", "k1", "k2", "k3")
DAMPING_TERMS: tuple[str, ...] = ("b0", "b1", "b2", "b3")
#: Name of the free touchdown intercept (spring part of the touchdown moment, N m).
INTERCEPT_NAME = "m0"
#: Full parameter vector order: intercept then the Eq. 3 terms.
PARAMETER_NAMES: tuple[str, ...] = (INTERCEPT_NAME,) + TERM_NAMES


@dataclass(frozen=True)
class StanceRegressors:
    """Everything of Eqs. 3-9 that is linear in the coefficients, for one stance.

    Every ``*_rows`` matrix has shape (N, 9) with columns in
    :data:`PARAMETER_NAMES` order ``[m0, k0, k1, k2, k3, b0, b1, b2, b3]``, so
    that the quantity at sample l is ``rows[l] @ theta``.

    Attributes
    ----------
    time_s : ndarray, shape (N,)
        Sample instants (s).
    delta_angle_rad : ndarray, shape (N,)
        d = rho - rho0 (rad), flexion positive.
    delta_velocity_rad_s : ndarray, shape (N,)
        w = omega - omega0 (rad/s).
    angular_velocity_rad_s : ndarray, shape (N,)
        omega (rad/s), flexion positive.
    rho0_rad, omega0_rad_s : float
        Touchdown angle (rad) and angular velocity (rad/s).
    moment_rows : ndarray, shape (N, 9)
        Joint moment M = M_s + M_d (N m, extensor positive), Eq. 5.
    spring_moment_rows, damper_moment_rows : ndarray, shape (N, 9)
        M_s and M_d (N m) separately (Eq. 4 with the touchdown split above);
        cached properties, built on first use.
    stiffness_rows, damping_rows : ndarray, shape (N, 9)
        K (N m/rad) and B (N m s/rad), Eq. 3.
    spring_energy_rows : ndarray, shape (N, 9)
        E_s = int M_s d(rho) (J) since touchdown, Eq. 8. A cached property:
        its k3 column is a second numerical integral, computed only when
        used (:meth:`spring_energy_columns` gives a column subset without it).
    damper_power_rows : ndarray, shape (N, 9)
        M_d * omega (W) = -P_d, Eq. 9 (the constraint is M_d * omega >= 0);
        a cached property (:meth:`damper_power_columns` gives a column subset).
    """

    time_s: np.ndarray
    delta_angle_rad: np.ndarray
    delta_velocity_rad_s: np.ndarray
    angular_velocity_rad_s: np.ndarray
    rho0_rad: float
    omega0_rad_s: float
    moment_rows: np.ndarray
    stiffness_rows: np.ndarray
    damping_rows: np.ndarray

    @property
    def n_samples(self) -> int:
        """Number of samples N in the stance."""
        return int(self.time_s.shape[0])

    @cached_property
    def spring_moment_rows(self) -> np.ndarray:
        """M_s (N m), shape (N, 9): the moment rows' spring columns m0, k0-k3 (damper columns 0)."""
        rows = self.moment_rows.copy()
        rows[:, _FIRST_DAMPER_COLUMN:] = 0.0
        return rows

    @cached_property
    def damper_moment_rows(self) -> np.ndarray:
        """M_d (N m), shape (N, 9): the moment rows' damper columns b0-b3 (spring columns 0)."""
        rows = self.moment_rows.copy()
        rows[:, :_FIRST_DAMPER_COLUMN] = 0.0
        return rows

    @cached_property
    def damper_power_rows(self) -> np.ndarray:
        """M_d * omega (W) = -P_d, Eq. 9, shape (N, 9) (the constraint is M_d * omega >= 0)."""
        return self.damper_moment_rows * self.angular_velocity_rad_s[:, None]

    def damper_power_columns(self, columns: np.ndarray) -> np.ndarray:
        """``damper_power_rows[:, columns]`` (W per coefficient unit), shape (N, p), without the full matrix."""
        columns = np.asarray(columns, dtype=int)
        sub = self.moment_rows[:, columns] * self.angular_velocity_rad_s[:, None]
        sub[:, columns < _FIRST_DAMPER_COLUMN] = 0.0
        return sub

    @cached_property
    def spring_energy_rows(self) -> np.ndarray:
        """E_s = int M_s d(rho) (J) since touchdown, Eq. 8, shape (N, 9) (computed on first use)."""
        rows = self._spring_energy_polynomial.copy()
        rows[:, _K3_COLUMN] = self._spring_energy_k3
        return rows

    def spring_energy_columns(self, columns: np.ndarray) -> np.ndarray:
        """``spring_energy_rows[:, columns]`` (J per coefficient unit), shape (N, p).

        The k3 column is the only one that needs an integral (a second
        Simpson integral, ``int (int w omega dt) omega dt``); it is computed,
        once, only when ``columns`` contains k3.
        """
        columns = np.asarray(columns, dtype=int)
        sub = self._spring_energy_polynomial[:, columns]
        is_k3 = columns == _K3_COLUMN
        if is_k3.any():
            sub[:, is_k3] = self._spring_energy_k3[:, None]
        return sub

    @cached_property
    def _spring_energy_polynomial(self) -> np.ndarray:
        """:attr:`spring_energy_rows` with the k3 column left 0: the closed-form columns, shape (N, 9)."""
        d = self.delta_angle_rad
        return _rows(d.size, {0: d, 1: d**2 / 2, 2: d**3 / 6, 3: d**4 / 12})

    @cached_property
    def _spring_energy_k3(self) -> np.ndarray:
        """k3 column of :attr:`spring_energy_rows`, ``int (int w omega dt) omega dt`` (J per N m s/rad^2), (N,)."""
        return cumulative_integral(self.moment_rows[:, _K3_COLUMN] * self.angular_velocity_rad_s, self.time_s)


#: Column of k3 in :data:`PARAMETER_NAMES` (the only spring-energy column needing an integral).
_K3_COLUMN = PARAMETER_NAMES.index("k3")
#: First damper column (b0) in :data:`PARAMETER_NAMES`: columns before it are spring (m0, k0-k3).
_FIRST_DAMPER_COLUMN = PARAMETER_NAMES.index("b0")


def _rows(n: int, columns: dict[int, np.ndarray | float]) -> np.ndarray:
    """(n, 9) rows with the given columns (index -> values or a constant) and zeros elsewhere."""
    rows = np.zeros((n, len(PARAMETER_NAMES)))
    for index, values in columns.items():
        rows[:, index] = values
    return rows


def cumulative_integral(values: np.ndarray, time_s: np.ndarray) -> np.ndarray:
    """Running integral from the first sample, same length as ``values``.

    Parameters
    ----------
    values : ndarray, shape (N,) or (N, k)
        Integrand sampled at ``time_s`` (integrated along axis 0).
    time_s : ndarray, shape (N,)
        Strictly increasing sample instants (s); non-uniform spacing allowed.

    Returns
    -------
    ndarray, same shape as ``values``
        Composite Simpson running integral (``scipy.integrate.cumulative_simpson``),
        0 at the first sample; trapezoidal for fewer than 3 samples.
    """
    values = np.asarray(values, float)
    if values.shape[0] < 3:
        out = np.zeros_like(values)
        if values.shape[0] == 2:
            out[1] = 0.5 * (values[0] + values[1]) * (time_s[1] - time_s[0])
        return out
    step = np.diff(time_s)
    if (np.abs(step - step[0]) <= 1e-9 * step[0]).all():  # uniform: scipy's faster path
        integral = cumulative_simpson(values, dx=float(step.mean()), axis=0)
    else:
        integral = cumulative_simpson(values, x=time_s, axis=0)
    # the leading 0 added here, not by scipy's ``initial=0.0`` (same array, a
    # quarter of the call's array-API overhead less)
    return np.concatenate((np.zeros((1,) + values.shape[1:]), integral))


def stance_regressors(
    time_s: np.ndarray, angle_rad: np.ndarray, angular_velocity_rad_s: np.ndarray
) -> StanceRegressors:
    """Build the linear-in-coefficients rows of Eqs. 3-9 for one joint and stance.

    Parameters
    ----------
    time_s : ndarray, shape (N,)
        Strictly increasing sample instants (s), N >= 2; sample 0 is touchdown.
    angle_rad : ndarray, shape (N,)
        Joint angle rho (rad), increasing with flexion.
    angular_velocity_rad_s : ndarray, shape (N,)
        omega = d(rho)/dt (rad/s), flexion positive.

    Returns
    -------
    StanceRegressors
        Rows for moment, spring/damper moment, K, B, spring energy and damper
        power; see the class docstring. Inputs are assumed finite (validated by
        :func:`hop_impedance.impedance.stance_fit.fit_joint_stance`).
    """
    t = np.asarray(time_s, float)
    rho = np.asarray(angle_rad, float)
    omega = np.asarray(angular_velocity_rad_s, float)
    n = t.shape[0]
    d = rho - rho[0]
    w = omega - omega[0]

    int_w_drho = cumulative_integral(w * omega, t)  # int (omega - omega0) d(rho)
    int_d_domega = d * w - int_w_drho  # by parts, d(t0) = 0

    # M = M_s + M_d: the spring (columns 0-4) and damper (5-8) parts have
    # disjoint columns, so each is the moment rows with the other part zeroed
    # (StanceRegressors.spring_moment_rows, .damper_moment_rows).
    moment = _rows(
        n, {0: 1.0, 1: d, 2: d**2 / 2, 3: d**3 / 3, 4: int_w_drho, 5: omega, 6: w**2 / 2, 7: w**3 / 3, 8: int_d_domega}
    )
    stiffness = _rows(n, {1: 1.0, 2: d, 3: d**2, 4: w})
    damping = _rows(n, {5: 1.0, 6: w, 7: w**2, 8: d})
    return StanceRegressors(
        time_s=t,
        delta_angle_rad=d,
        delta_velocity_rad_s=w,
        angular_velocity_rad_s=omega,
        rho0_rad=float(rho[0]),
        omega0_rad_s=float(omega[0]),
        moment_rows=moment,
        stiffness_rows=stiffness,
        damping_rows=damping,
    )


def parameter_indices(terms: tuple[str, ...] | list[str]) -> np.ndarray:
    """Column indices (into :data:`PARAMETER_NAMES`) of the intercept plus ``terms``.

    Parameters
    ----------
    terms : sequence of str
        Subset of :data:`TERM_NAMES`; the intercept m0 is always included first.

    Returns
    -------
    ndarray of int, shape (1 + len(terms),)
    """
    return np.array(_parameter_index_tuple(tuple(terms)), dtype=int)


@lru_cache(maxsize=256)
def _parameter_index_tuple(terms: tuple[str, ...]) -> tuple[int, ...]:
    """:func:`parameter_indices` as a tuple, computed once per term tuple."""
    unknown = [name for name in terms if name not in TERM_NAMES]
    if unknown:
        raise ValueError(f"unknown impedance terms {unknown}: allowed are {TERM_NAMES}")
    return (0,) + tuple(PARAMETER_NAMES.index(name) for name in terms)
