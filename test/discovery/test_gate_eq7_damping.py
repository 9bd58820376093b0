"""``stiffness_gate.GATE_EQ7_DAMPING`` (session 38, an option, off): a damping model's fold laws in the held-out gate
identified subject to seed 000's Eq. 7.

Our simulator's damping case at 2.2 Hz (seed 0, 8 hops, as ``bench/discovery_hit_rates.py --cases joint_damping
--freqs 2.2`` generates it): fitted on stances 0, 2, 4, 6 (the gate's fold 1) without the constraint the hip's b1 is
about 12 and ``B = b0 + b1 (omega - omega0)`` goes negative, and held-out stance 5 runs away (gap ~1e11; session 16
and ``bench/discovery_fold_damping_eq7.py``); with it B >= 0 on the training samples and stance 5 takes off with the
gap of the law fitted on all stances.
"""

from __future__ import annotations

import numpy as np

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery import stiffness_gate as sg
from hop_impedance.discovery.identify import identify
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import ModelSpec, feature_names
from hop_impedance.simulation.scenarios import Effects
from hop_impedance.simulation.sensors import SensorConfig
from hop_impedance.simulation.stance_set import EffectSizes, simulate_stance_set_recording


def test_the_gate_s_damping_folds_keep_eq7_and_the_held_out_stance_takes_off(monkeypatch):
    rec, _ = simulate_stance_set_recording(2.2, ("rigid",), 8, 0, Effects(angle_dependent_stiffness=False, damping=True,
                                           push_off=False), SensorConfig(), rtol=1e-6, sizes=EffectSizes(), redraws=10)
    trial = measure_trial(rec)
    fs._CONTEXT["rec"] = rec
    scales = fs.gap_scales(trial)
    spec, all_coefs = identify(ModelSpec(), trial, trial.stances, "joint_damping")
    train = [trial.stances[k] for k in (0, 2, 4, 6)]  # the gate's fold 1 (positions)
    held = trial.stances[5]
    b1 = feature_names(spec).index("b1")

    def fold_law():
        # as stiffness_gate.shoot_held_out identifies a fold's law
        eq7 = True if sg.GATE_EQ7_DAMPING and spec.has("joint_damping") else None
        return identify(spec, trial, train, eq7_fit=eq7)[1]

    free = fold_law()
    assert free[2, b1] > 8.0  # the hip's nonlinear damping the data do not hold
    assert fs.simulate_held_out(spec, free, trial, held, scales)["gap"] > 1e3
    monkeypatch.setattr(sg, "GATE_EQ7_DAMPING", True)
    eq7 = fold_law()
    dw = np.concatenate([s.omega_rad_s - s.omega_rad_s[0] for s in train])
    names = feature_names(spec)
    assert np.all(eq7[:, names.index("b0")] + eq7[:, b1] * dw >= -1e-6)
    r = fs.simulate_held_out(spec, eq7, trial, held, scales)
    pooled = fs.simulate_held_out(spec, all_coefs, trial, held, scales)["gap"]
    assert r["end_reason"] == "take_off" and r["gap"] < 2 * pooled < 0.05
