"""Coefficient recovery: simulate a trial, record it, analyse it, fit it, compare with the law.

The check of issue 5 ("recovery of known coefficients from simulated
stances"), shared by ``test/impedance/test_simulated_recordings.py`` and
``bench/recovery_errors.py``:

1. a push-off-free hopping trial on the hard surface (the push-off is not an
   Eq. 3 term), seed Table 2 stiffness at the trial's frequency;
2. its sensors sampled noise-free or with realistic noise and written as an
   MCAP recording with its truth;
3. ``analyze_recording`` (stance detection, filtering, kinematics, inverse
   dynamics) and ``fit_recording`` with the law's structure given;
4. per stance and joint, the relative error of k0 and k1 against the law.

Stances where the simulated law itself leaves the fit's feasible set (its K
or B below zero somewhere on the stance, which the seed's Eq. 7 forbids) are
counted, not compared: no constrained fit can return those coefficients.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from hop_impedance.biomech.filtering import DEFAULT_CUTOFF_HZ

JOINTS = ("ankle", "knee", "hip")
#: The fitted structure: the simulated law is K = k0 + k1 (rho - rho0), B = b0.
LAW_TERMS = ("k0", "k1", "b0")
#: Bootstrap resamples of :func:`median_interval`.
N_BOOT = 2000


def median_interval(values: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Median over axis 0 of ``values`` (n, k) and its 95 % bootstrap interval (lo, hi): ``N_BOOT`` resamples
    of the rows (stances) with replacement, percentiles 2.5 and 97.5 of their medians."""
    boot = np.median(values[rng.integers(0, len(values), (N_BOOT, len(values)))], axis=1)
    lo, hi = np.percentile(boot, [2.5, 97.5], axis=0)
    return np.median(values, axis=0), lo, hi


@dataclass
class RecoveryResult:
    """Per-stance k0/k1 errors of one or more trials (pooled with :meth:`extend`).

    Attributes
    ----------
    errors : dict
        joint -> list of ``[k0, k1]`` relative errors (fraction, fit / law - 1), one per compared stance.
    infeasible : dict
        joint -> number of stances whose law breaks Eq. 7 (not compared).
    z_scores : dict
        joint -> list of ``[k0, k1]`` errors in units of the fit's reported standard error
        ((fit - law) / SE); RMS near 1 means the reported uncertainty matches the scatter.
    rejected : dict
        joint -> rejection reasons of fits on compared stances (the stance is then not compared).
    fits : list
        ``fit_recording`` output per analysed stance (``{joint: JointImpedanceFit}``).
    trial_medians : list
        Per trial, joint -> median ``[k0, k1]`` error (NaN when no stance was compared).
    simulated_stances : int
        Stances the simulator produced.
    """

    errors: dict = field(default_factory=lambda: {j: [] for j in JOINTS})
    infeasible: dict = field(default_factory=lambda: {j: 0 for j in JOINTS})
    z_scores: dict = field(default_factory=lambda: {j: [] for j in JOINTS})
    rejected: dict = field(default_factory=lambda: {j: [] for j in JOINTS})
    fits: list = field(default_factory=list)
    trial_medians: list = field(default_factory=list)
    simulated_stances: int = 0

    def extend(self, other: RecoveryResult) -> None:
        """Pool another trial's stances into this result."""
        for joint in JOINTS:
            self.errors[joint] += other.errors[joint]
            self.infeasible[joint] += other.infeasible[joint]
            self.rejected[joint] += other.rejected[joint]
            self.z_scores[joint] += other.z_scores[joint]
        self.fits += other.fits
        self.trial_medians += other.trial_medians
        self.simulated_stances += other.simulated_stances

    def error_array(self, joint: str) -> np.ndarray:
        """Relative k0/k1 errors of the compared stances, shape (n, 2)."""
        return np.asarray(self.errors[joint], float).reshape(-1, 2)


def law_breaks_eq7(true_stance: dict, joint_index: int) -> bool:
    """True when the simulated law's own K or B is below zero somewhere on the true stance samples.

    Uses the truth file's law (``impedance``: k0..k3, b0..b3 with its rho0,
    omega0) on the simulator's own angle and rate samples. Example: 1.53 Hz,
    hip, first stance of seed 11: K reaches -46 N m/rad where the hip extends
    0.9 rad past its touchdown angle.
    """
    imp = true_stance["impedance"][JOINTS[joint_index]]
    samples = true_stance["samples"]
    d = np.asarray(samples["rho_rad"], float)[:, joint_index] - imp["rho0_rad"]
    w = np.asarray(samples["omega_rad_s"], float)[:, joint_index] - imp["omega0_rad_s"]
    stiffness = imp["k0"] + imp["k1"] * d + imp["k2"] * d**2 + imp["k3"] * w
    damping = imp["b0"] + imp["b1"] * w + imp["b2"] * w**2 + imp["b3"] * d
    return bool(stiffness.min() < 0.0 or damping.min() < 0.0)


def recover_trial(
    freq_hz: float,
    seed: int,
    noisy: bool,
    folder: Path,
    *,
    n_hops: int = 4,
    cutoff_hz: float = DEFAULT_CUTOFF_HZ,
    edge_s: float = 0.0,
    skip_first: int = 0,
    trial=None,
    noise_stream: int = 1,
) -> RecoveryResult:
    """Simulate (or reuse ``trial``), record, analyse and fit one trial; k0/k1 errors per stance.

    Parameters
    ----------
    freq_hz : float
        Hopping frequency (Hz); the law uses seed Table 2 at that frequency.
    seed : int
        Hop-to-hop variability seed of the simulation; the sensor noise uses ``[seed, 1]``.
    noisy : bool
        Realistic sensor noise (1 mm markers, 2 N force, 0.5 N m torque) or none.
    folder : Path
        Where the MCAP recording is written.
    n_hops : int
        Hops simulated (the trial may stop earlier: without push-off it loses energy).
    cutoff_hz : float
        Marker and force low-pass cut-off of the analysis (Hz).
    edge_s : float
        Time left out of the objective at each stance edge (s), ``FitOptions.exclude_*``.
    skip_first : int
        Simulated stances left out at the start of the trial (the first lands from
        the same lead-in in every seed's trial; the seed paper discarded its first hops).
    trial : HoppingTrial, optional
        An already simulated trial of ``freq_hz`` and ``seed`` (saves the simulation
        when the same trial is recorded twice).
    noise_stream : int
        The sensor noise draw, ``[seed, noise_stream]``: another value samples the same trial
        with other noise (how far the noisy medians move from the noise draw alone).
    """
    from hop_impedance.biomech.analysis import AnalysisOptions, analyze_recording
    from hop_impedance.impedance.recording_fits import fit_recording
    from hop_impedance.io.recording_io import load_recording
    from hop_impedance.simulation.simulate import write_simulated_recording

    if trial is None:
        trial = simulate_law_trial(freq_hz, seed, n_hops)
    rec, truth = record_law_trial(trial, noisy, np.random.default_rng([seed, noise_stream]))
    path = Path(folder) / f"recovery_{freq_hz:.2f}hz_seed{seed}_{'noisy' if noisy else 'clean'}.mcap"
    write_simulated_recording(path, rec, truth)
    analysis = analyze_recording(load_recording(path), AnalysisOptions(marker_cutoff_hz=cutoff_hz, force_cutoff_hz=cutoff_hz))
    fits = fit_recording(analysis, law_fit_options(analysis.options, edge_s))
    result = compare_with_law(analysis, fits, truth, skip_first=skip_first)
    result.trial_medians.append(
        {j: np.median(result.error_array(j), axis=0) if result.errors[j] else np.full(2, np.nan) for j in JOINTS}
    )
    return result


def record_law_trial(trial, noisy: bool, rng: np.random.Generator) -> tuple:
    """(recording, truth) of a push-off-free law trial: its sensors sampled noise-free or with realistic noise.

    The truth is :func:`~hop_impedance.simulation.truth.trial_truth` for the seed's mean subject with the
    push-off switched off (``Effects(push_off=False)``, the law :func:`simulate_law_trial` uses).
    """
    from hop_impedance.biomech.body_model import body_model_from_stature
    from hop_impedance.simulation.scenarios import SEED_SUBJECT, Effects
    from hop_impedance.simulation.sensors import SensorConfig, noise_free, sample_recording
    from hop_impedance.simulation.truth import trial_truth

    sensors = SensorConfig() if noisy else noise_free(SensorConfig())
    rec, sensor_truth = sample_recording(trial, sensors, SEED_SUBJECT, rng)
    truth = trial_truth(trial, sensors, SEED_SUBJECT, body_model_from_stature(SEED_SUBJECT),
                        Effects(push_off=False).to_dict(), sensor_truth, {})
    return rec, truth


def law_fit_options(analysis_options, edge_s: float):
    """Fit options of the recovery: the law's structure given (:data:`LAW_TERMS`, no term elimination),
    ``edge_s`` left out of the objective at each stance edge (``FitOptions.exclude_*``)."""
    from hop_impedance.impedance.recording_fits import default_fit_options

    return replace(default_fit_options(analysis_options), reduce=False, terms=LAW_TERMS, exclude_touchdown_s=edge_s,
                   exclude_takeoff_s=edge_s)


def compare_with_law(analysis, fits, truth: dict, *, skip_first: int = 0, law_scale: float = 1.0) -> RecoveryResult:
    """Per stance and joint, the fitted k0/k1 against ``law_scale`` x the truth's law (stances matched by touchdown).

    ``law_scale`` is 0.5 for one leg of a two-leg recording built from one
    lumped trial (:mod:`hop_impedance.validation.bilateral_recovery`).
    """
    result = RecoveryResult(fits=fits, simulated_stances=len(truth["stances"]))
    truth_by_touchdown = {round(s["touchdown_s"], 2): s for s in truth["stances"]}
    for stance, stance_fits in zip(analysis.stances, fits):
        true = truth_by_touchdown.get(round(stance.touchdown_s, 2))
        if true is None or stance.rejection_reason is not None or true["index"] < skip_first:
            continue
        for j, joint in enumerate(JOINTS):
            fit = stance_fits[joint]
            if law_breaks_eq7(true, j):
                result.infeasible[joint] += 1
            elif not fit.ok:
                result.rejected[joint].append(fit.rejection_reason)
            else:
                law = {k: law_scale * true["impedance"][joint][k] for k in ("k0", "k1")}
                result.errors[joint].append([fit.coefficients[k] / law[k] - 1.0 for k in ("k0", "k1")])
                result.z_scores[joint].append([(fit.coefficients[k] - law[k]) / fit.std_errors[k] for k in ("k0", "k1")])
    return result


def simulate_law_trial(freq_hz: float, seed: int, n_hops: int = 4):
    """The push-off-free hard-surface hopping trial :func:`recover_trial` records (seed Table 2 law)."""
    from hop_impedance.simulation.hopping_trial import simulate_hopping
    from hop_impedance.simulation.scenarios import Effects, hopping_config

    chain, config = hopping_config(freq_hz, "hard", n_hops, Effects(push_off=False))
    return simulate_hopping(chain, config, seed=seed)


def recover_pooled(
    freq_hz: float,
    seeds,
    folder: Path,
    *,
    cutoff_hz: dict[str, float],
    n_hops: int = 4,
    edge_s: float = 0.0,
    skip_first: int = 0,
    noise_stream: int = 1,
) -> dict[str, RecoveryResult]:
    """Every seed's trial at one frequency, recorded noise-free and noisy, recovered and pooled.

    Each trial is simulated once and sampled twice. ``cutoff_hz`` maps
    ``"clean"`` and ``"noisy"`` to the analysis cut-off (Hz) of that
    recording; the other arguments (``noise_stream``: the noise draw) as in :func:`recover_trial`.

    Returns
    -------
    ``{"clean": RecoveryResult, "noisy": RecoveryResult}``
    """
    out = {"clean": RecoveryResult(), "noisy": RecoveryResult()}
    for seed in seeds:
        trial = simulate_law_trial(freq_hz, seed, n_hops)
        for label, result in out.items():
            result.extend(recover_trial(freq_hz, seed, label == "noisy", folder, n_hops=n_hops, cutoff_hz=cutoff_hz[label],
                                        edge_s=edge_s, skip_first=skip_first, trial=trial,
                                        noise_stream=noise_stream))
    return out
