"""The law whose per-stance Eq. 3 fit returns seed Table 2 (issue 17's seed-like hopper).

Seed 000's Table 2 coefficients are what its Eq. 3 fit *returned* on its subjects' stances, not the
moments' generating law. On our seed-like hopper the elastic moment is ``a(t) (k0 dr + k1 dr^2 / 2)`` with
the bell activation ``a(t)`` (:class:`~hop_impedance.simulation.impedance_laws.BellActivation`) and a
push-off late in stance, and the fit ``K(rho) = k0 + k1 (rho - rho0)`` reads the bell, which peaks with
the flexion, as more angle dependence and less initial stiffness (docs/simulator.md). So the law simulated
is the one whose fit returns Table 2, found by one rule at every frequency (:func:`calibrate_law_scale`):

    the law's (k0, k1) such that the fit returns Table 2, per joint (ankle and knee), found by steps
    of :func:`next_scale` (damped scale x sqrt(Table 2 / fitted), then secant steps on the affine map)

where *fitted* is the median over the analysed stances (all complete stances after the first) of the
per-stance fit with the terms k0, k1, b0 that ``hop-impedance analyze --model-terms k0,k1,b0`` makes, on a
noise-free recording analysed from its markers and force plate exactly as the realism bench does
(bench/simulator_realism.py --seed-like --fits). The hip is left at Table 2 (its fit is dominated by the
trunk-balance moment, which is not part of the Eq. 3 law; the truth file states the whole hip law).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hop_impedance.simulation.scenarios import SEED_TABLE2, Effects, nearest_table2
from hop_impedance.simulation.sensors import SensorConfig, noise_free

#: Joints whose law the rule scales (indices into ankle, knee, hip).
CALIBRATED_JOINTS = (0, 1)
#: The fit's terms (``analyze --model-terms``) and the stances summarised: the median after the first.
FIT_TERMS = ("k0", "k1", "b0")
#: Largest change of a scale factor in one step of :func:`next_scale`.
MAX_STEP_FACTOR = 1.5


def fitted_k0_k1(recording) -> np.ndarray:
    """Median per-stance fitted (k0, k1) per joint, shape (2, 3), over the complete stances after the first.

    The analysis and fit are the ones ``hop-impedance analyze --model-terms k0,k1,b0`` runs (markers and
    force plate, 12 Hz low-pass, 2D inverse dynamics; every joint fitted with the given terms).
    """
    from hop_impedance.biomech.analysis import analyze_recording

    return median_k0_k1(seed_model_fits(analyze_recording(recording)))


def seed_model_fits(analysis) -> list[dict]:
    """Per stance ``{joint: fit}`` with the terms :data:`FIT_TERMS`, the complete fitted stances after the first.

    ``analysis``: :func:`~hop_impedance.biomech.analysis.analyze_recording`'s result.
    """
    from hop_impedance.impedance.recording_fits import fit_recording_trial, given_structure

    structure = given_structure(FIT_TERMS, "law calibration (simulation/fit_calibration.py)")
    trial = fit_recording_trial(analysis, structures={j: structure for j in ("ankle", "knee", "hip")})
    kept = [fits for stance, fits in zip(analysis.stances, trial.fits)
            if stance.complete and stance.joints is not None and all(f.rejection_reason is None for f in fits.values())]
    return kept[1:]  # the first stance lands from the lead-in


def median_k0_k1(stance_fits: list[dict]) -> np.ndarray:
    """Median over stances of the fitted (k0, k1) per joint, shape (2, 3) (:func:`seed_model_fits`' stances)."""
    if not stance_fits:
        raise ValueError("no fitted complete stance after the first")
    rows = [[[fits[j].coefficients[c] for j in ("ankle", "knee", "hip")] for c in ("k0", "k1")] for fits in stance_fits]
    return np.median(np.array(rows, float), axis=0)


@dataclass
class Calibration:
    """Outcome of :func:`calibrate_law_scale` at one frequency."""

    freq_hz: float
    scale: np.ndarray  # (2, 3): factors on Table 2's k0 (row 0) and k1 (row 1), ankle, knee, hip
    fitted: np.ndarray  # (2, 3): the fit with that scale
    history: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)  # (scale, fitted) per step

    def deviation(self) -> np.ndarray:
        """Fitted over Table 2 minus 1, shape (2, 3)."""
        return self.fitted / table2_k(self.freq_hz) - 1.0


def table2_k(freq_hz: float) -> np.ndarray:
    """Seed Table 2's (k0, k1) per joint at its frequency nearest ``freq_hz``, shape (2, 3)."""
    row = SEED_TABLE2[nearest_table2(freq_hz)]
    return np.array([row["k0"], row["k1"]], float)


def next_scale(history: list[tuple[np.ndarray, np.ndarray]], target: np.ndarray, joint: int,
               ratio: np.ndarray) -> np.ndarray:
    """One joint's next (k0, k1) scale: the secant step, trust-limited, or the damped multiplicative step.

    The fit's (k0, k1) is near affine in the law's (k0, k1) for a given hop, but the bell couples them (the
    ankle's fitted k0 moves ~1.6 x its law's and k1's the opposite way; bench/simulator_law_calibration.py), so
    ``scale x Table 2 / fitted`` alone oscillates (1.87 Hz ankle k0 -54, +108, -48, +105 %). With fewer than
    three measured steps, the damped rule ``scale x sqrt(Table 2 / fitted)``; then the affine map fitted by least
    squares to the last (up to four) steps is solved for Table 2, the change limited to a factor
    :data:`MAX_STEP_FACTOR` per coefficient (and the damped rule if that map is singular or the solution not
    positive).
    """
    current = history[-1][0][:, joint]
    damped = current * np.sqrt(np.clip(ratio, 1.0 / MAX_STEP_FACTOR**2, MAX_STEP_FACTOR**2))
    if len(history) < 3:
        return damped
    recent = history[-4:]
    x = np.array([[h[0][0, joint], h[0][1, joint], 1.0] for h in recent])
    y = np.array([h[1][:, joint] for h in recent])
    coef = np.linalg.lstsq(x, y, rcond=None)[0]  # (3, 2): fitted = [s0, s1, 1] @ coef
    try:
        solution = np.linalg.solve(coef[:2].T, target[:, joint] - coef[2])
    except np.linalg.LinAlgError:
        return damped
    if not np.all(np.isfinite(solution)) or np.any(solution <= 0):
        return damped
    return np.clip(solution, current / MAX_STEP_FACTOR, current * MAX_STEP_FACTOR)


def calibrate_law_scale(freq_hz: float, options: dict, *, start=None, n_hops: int = 6, seed: int = 1,
                        iterations: int = 6, tolerance: float = 0.05, on_step=None,
                        surface: str = "hard") -> Calibration:
    """Step the ankle's and knee's scale (:func:`next_scale`) until every fitted k0, k1 is within ``tolerance``.

    ``options`` are :func:`~hop_impedance.simulation.simulate.simulate_recording`'s keyword options (e.g.
    :func:`~hop_impedance.simulation.scenarios.seed_like_options` without ``law_scale``); ``start`` the
    first scale (2, 3) (default ones: Table 2). Each step simulates a noise-free ``n_hops`` trial on ``surface``
    (default seed 001's hard surface) with the scaled law and fits it (:func:`fitted_k0_k1`); a law with which the trial fails (no
    periodic hop) is replaced by the geometric mean of it and the last measured scale. Stops when the worst
    ankle/knee deviation is within ``tolerance`` or after ``iterations`` trials, and returns the measured step
    with the smallest worst deviation (the caller checks :meth:`Calibration.deviation`). ``on_step(scale,
    fitted or None, error or None)`` is called after every trial.
    """
    from hop_impedance.simulation.simulate import simulate_recording

    target = table2_k(freq_hz)
    scale = np.ones((2, 3)) if start is None else np.array(start, float).reshape(2, 3)
    options = {k: v for k, v in options.items() if k != "law_scale"}
    history: list[tuple[np.ndarray, np.ndarray]] = []
    for _ in range(max(1, iterations)):
        try:
            rec, _truth = simulate_recording(freq_hz, surface, n_hops, seed=seed, sensors=noise_free(SensorConfig()),
                                             effects=Effects(), law_scale={freq_hz: scale.copy()}, **options)
            fitted = fitted_k0_k1(rec)
        except ValueError as exc:  # no periodic hop with this law (e.g. "take-off too weak"): half the step back
            if not history:
                raise
            if on_step is not None:
                on_step(scale.copy(), None, str(exc))
            scale = np.sqrt(scale * history[-1][0])
            continue
        history.append((scale.copy(), fitted))
        if on_step is not None:
            on_step(scale.copy(), fitted, None)
        ratio = target / fitted
        if worst_deviation(fitted, target) <= tolerance:
            break
        for j in CALIBRATED_JOINTS:
            scale[:, j] = next_scale(history, target, j, ratio[:, j])
    if not history:
        raise ValueError(f"{freq_hz} Hz: no trial could be fitted")
    best_scale, best_fit = min(history, key=lambda h: worst_deviation(h[1], target))
    return Calibration(freq_hz, best_scale, best_fit, history)


def worst_deviation(fitted: np.ndarray, target: np.ndarray) -> float:
    """Largest |fitted / target - 1| over the calibrated joints' k0 and k1."""
    return float(np.max(np.abs(fitted[:, CALIBRATED_JOINTS] / target[:, CALIBRATED_JOINTS] - 1.0)))
