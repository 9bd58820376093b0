"""One call from high-level choices to a contract recording plus its truth document."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.recording import Recording, Subject
from hop_impedance.simulation.hopping_trial import simulate_hopping
from hop_impedance.simulation.scenarios import SEED_SUBJECT, Effects, hopping_config
from hop_impedance.simulation.sensors import SensorConfig, sample_recording
from hop_impedance.simulation.truth import trial_truth, truth_path, write_truth


def simulate_recording(
    freq_hz: float = 2.2, surface_name: str = "hard", n_hops: int = 10, seed: int = 1, effects: Effects = Effects(),
    sensors: SensorConfig = SensorConfig(), *, subject: Subject = SEED_SUBJECT, tuned_for: str | None = None,
    generator: dict | None = None, **options,
) -> tuple[Recording, dict]:
    """Simulate a hopping trial and sample it as a contract recording.

    Parameters
    ----------
    freq_hz : float
        Target hop frequency (Hz); stiffness from seed Table 2 (interpolated).
    surface_name : {"hard", "soft", "rigid"}
        Surface under every hop unless ``unexpected_surface`` is given.
    n_hops, seed : int
        Hops; the seed of hop-to-hop variability and sensor noise.
    effects : Effects
        Which law effects are present.
    sensors : SensorConfig
        Rates and sensor effects.
    subject : Subject
        Default the seed's mean subject (54.8 kg, 1.63 m, female).
    tuned_for : str, optional
        Surface the law (touchdown speed, push-off) is calibrated on; default
        ``surface_name``. Tuned for soft and run on hard = seed 001's
        unexpected hard surface for every hop.
    generator : dict, optional
        Stored as is in the truth file (e.g. the command line).
    **options
        The hopper's choices, keyword arguments of :func:`~hop_impedance.simulation.scenarios.hopping_config` (one
        place for their defaults): ``touchdown_rho_rad``, ``unexpected_surface`` / ``unexpected_hops`` (a surface
        swapped in, without re-tuning, on the listed 0-based hops), ``variability`` (seeded hop-to-hop variability,
        default on), ``trunk_balance``, ``flight``, ``landing``, ``contact_ahead_m``, ``push_timing``,
        ``bell_activation_min``, ``law_scale``, ``pad``, ``push_weights``, ``push_off_gain``, ``passive_takeoff_s``,
        ``passive_landing_s``, ...; :func:`~hop_impedance.simulation.scenarios.seed_like_options` bundles issue 17's
        candidate.

    Returns
    -------
    (recording : Recording, truth : dict, see :mod:`hop_impedance.simulation.truth`)
    """
    chain, config = hopping_config(freq_hz, surface_name, n_hops, effects, subject=subject,
                                   calibration_surface=tuned_for, **options)
    trial = simulate_hopping(chain, config, seed=seed)
    recording, sensor_truth = sample_recording(trial, sensors, subject, np.random.default_rng([seed, 1]))
    gen = {"seed": seed, "freq_hz": freq_hz, "surface": surface_name, "n_hops": n_hops,
           "tuned_for": tuned_for or surface_name, **(generator or {})}
    truth = trial_truth(trial, sensors, subject, body_model_from_stature(subject), effects.to_dict(), sensor_truth, gen)
    return recording, truth


def write_simulated_recording(out_path: str | Path, recording: Recording, truth: dict) -> Path:
    """Write ``out_path`` (MCAP, contract) and ``<stem>.truth.json`` next to it; returns the truth path."""
    from hop_impedance.io.recording_io import save_recording

    out = Path(out_path)
    if out.suffix != ".mcap":
        raise ValueError(f"output must end in .mcap, got {out.name!r}")
    out.parent.mkdir(parents=True, exist_ok=True)
    save_recording(out, recording)
    tpath = truth_path(out)
    write_truth(tpath, truth)
    return tpath
