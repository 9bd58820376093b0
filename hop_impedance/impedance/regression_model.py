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
from numpy.typing import NDArray
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
        M_s and M_d (N m) separately (Eq. 4 with the touchdown split above).
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
    spring_moment_rows: np.ndarray
    damper_moment_rows: np.ndarray
    stiffness_rows: np.ndarray
    damping_rows: np.ndarray

    @property
    def n_samples(self) -> int:
        """Number of samples N in the stance."""
        return int(self.time_s.shape[0])

    @cached_property
    def damper_power_rows(self) -> np.ndarray:
        """M_d * omega (W) = -P_d, Eq. 9, shape (N, 9) (the constraint is M_d * omega >= 0)."""
        return damper_power_regressors(self.damper_moment_rows, self.angular_velocity_rad_s)

    def damper_power_columns(self, columns: np.ndarray) -> np.ndarray:
        """``damper_power_rows[:, columns]`` (W per coefficient unit), shape (N, p), without the full matrix."""
        return damper_power_regressors(self.damper_moment_rows[:, np.asarray(columns, dtype=int)],
                                       self.angular_velocity_rad_s)

    @cached_property
    def spring_energy_rows(self) -> np.ndarray:
        """E_s = int M_s d(rho) (J) since touchdown, Eq. 8, shape (N, 9) (computed on first use)."""
        rows: np.ndarray = self._spring_energy_polynomial.copy()
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
        return spring_energy_polynomial_regressors(self.delta_angle_rad)

    @cached_property
    def _spring_energy_k3(self) -> np.ndarray:
        """k3 column of :attr:`spring_energy_rows`, ``int (int w omega dt) omega dt`` (J per N m s/rad^2), (N,)."""
        return spring_energy_k3_regressor(self.moment_rows[:, _K3_COLUMN], self.angular_velocity_rad_s, self.time_s)


#: Column of k3 in :data:`PARAMETER_NAMES` (the only spring-energy column needing an integral).
_K3_COLUMN = PARAMETER_NAMES.index("k3")
#: Column of each parameter name in every ``*_rows`` matrix.
_COLUMN: dict[str, int] = {name: index for index, name in enumerate(PARAMETER_NAMES)}


def coefficient_rows(n: int, **terms: np.ndarray | float) -> np.ndarray:
    """(n, 9) rows of a quantity linear in the parameters, from its term of each named coefficient.

    ``coefficient_rows(n, k0=1.0, k1=d)`` is the quantity ``k0 + k1 d``: the
    column of each named parameter (:data:`PARAMETER_NAMES`) holds what
    multiplies it (a value per sample or a constant), every other column 0.
    """
    rows = np.zeros((n, len(PARAMETER_NAMES)))
    for name, values in terms.items():
        rows[:, _COLUMN[name]] = values
    return rows


# -- the seed's equations, one function each (d = rho - rho0, w = omega - omega0) --------------------
def stiffness_regressors(d: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Eq. 3, stiffness ``K = k0 + k1 d + k2 d**2 + k3 w`` (N m/rad), rows (N, 9)."""
    return coefficient_rows(d.size, k0=1.0, k1=d, k2=d**2, k3=w)


def damping_regressors(d: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Eq. 3, damping ``B = b0 + b1 w + b2 w**2 + b3 d`` (N m s/rad), rows (N, 9)."""
    return coefficient_rows(d.size, b0=1.0, b1=w, b2=w**2, b3=d)


def spring_moment_regressors(d: np.ndarray, int_w_drho: np.ndarray) -> np.ndarray:
    """Eq. 4, spring moment ``M_s = m0 + int K d(rho)`` (N m), rows (N, 9).

    ``M_s = m0 + k0 d + k1 d**2/2 + k2 d**3/3 + k3 int w d(rho)``, with
    ``int_w_drho`` = ``int_t0^t w omega dt`` (path dependent, integrated
    numerically) and m0 the spring part of the touchdown moment (module docstring).
    """
    return coefficient_rows(d.size, m0=1.0, k0=d, k1=d**2 / 2, k2=d**3 / 3, k3=int_w_drho)


def damper_moment_regressors(omega: np.ndarray, w: np.ndarray, int_d_domega: np.ndarray) -> np.ndarray:
    """Eq. 4, damper moment ``M_d = M_d0 + int B d(omega)`` (N m), rows (N, 9).

    ``M_d = b0 omega + b1 w**2/2 + b2 w**3/3 + b3 int d d(omega)``: the
    touchdown part ``M_d0 = b0 omega0`` is the linear damper at the touchdown
    damping (module docstring), so ``b0 omega0 + b0 w = b0 omega``.
    """
    return coefficient_rows(omega.size, b0=omega, b1=w**2 / 2, b2=w**3 / 3, b3=int_d_domega)


def joint_moment_regressors(spring_moment_rows: NDArray[np.float64], damper_moment_rows: NDArray[np.float64]) -> np.ndarray:
    """Eq. 5, joint moment ``M = M_s + M_d`` (N m, extensor positive), rows (N, 9).

    The two parts have disjoint columns (m0, k0-k3 and b0-b3), so the sum
    holds each part's numbers unchanged.
    """
    return spring_moment_rows + damper_moment_rows


def spring_energy_polynomial_regressors(d: np.ndarray) -> np.ndarray:
    """Eq. 8, spring energy ``E_s = int_t0^t M_s d(rho)`` (J) without its k3 term, rows (N, 9).

    Closed form of the integral of Eq. 4's M_s: ``m0 d + k0 d**2/2 +
    k1 d**3/6 + k2 d**4/12``; the k3 column (a path integral) is
    :func:`spring_energy_k3_regressor`, left 0 here.
    """
    return coefficient_rows(d.size, m0=d, k0=d**2 / 2, k1=d**3 / 6, k2=d**4 / 12)


def spring_energy_k3_regressor(int_w_drho: np.ndarray, omega: np.ndarray, time_s: np.ndarray) -> np.ndarray:
    """Eq. 8, the k3 column of the spring energy: ``int_t0^t (int w d(rho)) omega dt`` (J per N m s/rad^2), (N,)."""
    return cumulative_integral(int_w_drho * omega, time_s)


def damper_power_regressors(damper_moment_rows: NDArray[np.float64], omega: NDArray[np.float64]) -> np.ndarray:
    """Eq. 9, damper power written as ``M_d omega = -P_d`` (W), rows of the same shape as ``damper_moment_rows``.

    The constraint ``P_d <= 0`` is ``M_d omega >= 0``; columns of
    ``damper_moment_rows`` (all nine or a subset) are multiplied sample by sample.
    """
    return damper_moment_rows * omega[:, None]


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
    d = rho - rho[0]
    w = omega - omega[0]
    int_w_drho = cumulative_integral(w * omega, t)  # int (omega - omega0) d(rho)
    int_d_domega = d * w - int_w_drho  # by parts, d(t0) = 0
    spring = spring_moment_regressors(d, int_w_drho)
    damper = damper_moment_regressors(omega, w, int_d_domega)
    return StanceRegressors(
        time_s=t,
        delta_angle_rad=d,
        delta_velocity_rad_s=w,
        angular_velocity_rad_s=omega,
        rho0_rad=float(rho[0]),
        omega0_rad_s=float(omega[0]),
        moment_rows=joint_moment_regressors(spring, damper),
        spring_moment_rows=spring,
        damper_moment_rows=damper,
        stiffness_rows=stiffness_regressors(d, w),
        damping_rows=damping_regressors(d, w),
    )


@dataclass(frozen=True)
class StanceProblem:
    """One joint in one stance as the fit sees it: the regressors and what enters Eq. 6.

    Attributes
    ----------
    regressors : StanceRegressors
        Rows of Eqs. 3-9 at every sample from touchdown (the constraints hold at all of them).
    window : ndarray of bool, shape (N,)
        Samples entering the objective (Eq. 6), the F-tests and the fit errors.
    moment_rows : ndarray, shape (n, 9)
        ``regressors.moment_rows`` in the window: every candidate model takes a column subset.
    moment_nm : ndarray, shape (n,)
        Measured moment tau (N m) in the window.
    time_s : ndarray, shape (n,)
        Sample instants (s) in the window.
    """

    regressors: StanceRegressors
    window: np.ndarray
    moment_rows: np.ndarray
    moment_nm: np.ndarray
    time_s: np.ndarray

    def in_window(self, values: np.ndarray) -> np.ndarray:
        """``values[window]`` (the array itself when the window is the whole stance)."""
        return values if self.window.all() else values[self.window]

    def design(self, terms: tuple[str, ...]) -> np.ndarray:
        """Moment rows X (n, 1 + len(terms)) of the intercept and ``terms`` in the window."""
        return self.moment_rows[:, parameter_indices(terms)]


def stance_problem(
    time_s: np.ndarray, angle_rad: np.ndarray, angular_velocity_rad_s: np.ndarray, moment_nm: np.ndarray,
    window: np.ndarray,
) -> StanceProblem:
    """Regressors of one stance (:func:`stance_regressors`) and the rows and moment of its fit ``window`` (bool, (N,))."""
    regressors = stance_regressors(time_s, angle_rad, angular_velocity_rad_s)
    whole = bool(window.all())  # the default: nothing excluded, no windowed copies needed
    def pick(values: np.ndarray) -> np.ndarray:
        return values if whole else values[window]
    return StanceProblem(regressors, window, pick(regressors.moment_rows), pick(np.asarray(moment_nm, float)),
                         pick(regressors.time_s))


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
