"""The thigh/HAT mass split chosen by the baseline's forward gap (hop_impedance.discovery.body_nuisance).

Checked against known truths, both ways: a second-generator recording (Winter's segment table: thighs
about 20 % of body mass where the analysis' de Leva table has 29.6 %) must get its thigh and HAT masses
back; a recording of our own simulator, whose body *is* the analysis' de Leva table, must keep the table
(a rule that always moved mass, or never did, fails one of the two).
"""

from __future__ import annotations

import pytest

from hop_impedance.discovery.body_nuisance import choose_body
from hop_impedance.discovery.measurement import measure_trial, split_overrides
from hop_impedance.simulation.scenarios import Effects
from hop_impedance.simulation.stance_set import simulate_stance_set_recording
from hop_impedance.validation.strict_generator import StrictConfig, strict_recording


def test_split_overrides_move_thigh_mass_to_the_hat_and_keep_the_total():
    rec, _ = strict_recording(StrictConfig(seed=5, hops=6))
    model = measure_trial(rec).chain
    from hop_impedance.biomech.analysis import analyze_recording

    body = analyze_recording(rec).model
    ov = split_overrides(body, 0.25)
    assert ov["thigh"]["mass_kg"] == pytest.approx(0.75 * body.thigh.mass_kg)
    assert ov["thigh"]["mass_kg"] + ov["hat"]["mass_kg"] == pytest.approx(body.thigh.mass_kg + body.hat.mass_kg)
    # radius of gyration kept: inertia scales with mass
    assert ov["hat"]["inertia_kgm2"] / ov["hat"]["mass_kg"] == pytest.approx(body.hat.inertia_kgm2 / body.hat.mass_kg)
    assert model.mass_kg.sum() == pytest.approx(body.total_mass_kg)


@pytest.mark.slow
def test_a_winter_body_gets_its_thigh_and_hat_masses_back():
    """Strict null, seed 5, 6 hops: the generator's thigh / HAT masses (truth) against the table's and the
    chosen ones. Measured: thigh table / chosen / true 17.7 / 9.4 / 11.7 kg (the table's error 6.1 kg, the
    chosen split's 2.3 kg); the baseline's in-sample forward gap falls by more than half."""
    rec, truth = strict_recording(StrictConfig(seed=5, hops=6))
    _, choice = choose_body(rec, measure_trial(rec))
    true_thigh, true_hat = truth["subject"]["mass_kg"][2], truth["subject"]["mass_kg"][3]
    table_thigh, chosen_thigh = choice.thigh_mass_kg
    table_hat, chosen_hat = choice.hat_mass_kg
    assert abs(table_thigh - true_thigh) > 4.0, choice.as_json()  # the table is far off: something to find
    # the split is an effective parameter (it also absorbs the HAT's other differences), so it is judged by
    # how much of the table's error it removes, not by an exact match
    assert abs(chosen_thigh - true_thigh) < 0.5 * abs(table_thigh - true_thigh), choice.as_json()
    assert abs(chosen_hat - true_hat) < 0.5 * abs(table_hat - true_hat), choice.as_json()
    assert choice.gap_chosen < 0.5 * choice.gap_table


@pytest.mark.slow
def test_our_simulators_de_leva_body_keeps_the_table():
    """Our simulator's body is the analysis' de Leva table: the search keeps it (fraction 0) or moves less
    than 5 % of the thigh mass."""
    rec = simulate_stance_set_recording(2.2, ("rigid",), 6, seed=2, rtol=1e-6,
                                        effects=Effects(angle_dependent_stiffness=False, damping=False,
                                                        push_off=False))[0]
    _, choice = choose_body(rec, measure_trial(rec))
    assert abs(choice.fraction) < 0.05, choice.as_json()
