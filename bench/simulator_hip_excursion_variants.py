"""Issue 17, session 12: what each candidate mechanism for the seed's hip excursion moves, in the simulator's own terms.

Usage::

    nice -n 19 .venv/bin/python bench/simulator_hip_excursion_variants.py                      # every variant
    nice -n 19 .venv/bin/python bench/simulator_hip_excursion_variants.py --variants base,push_0.7_1.0 --freqs 2.2

Every variant is the rigid-plate candidate of session 11 (``seed_like_options()``, bell a_min 0.9, the law
``bell09_rigid_pad15_3`` of bench/simulator_issue17.py, rigid plate + 15 mm n 3 shoe pad) with one mechanism
changed, the same at every frequency (no per-frequency tuning):

- ``push_A_D``: the push-off from A for D of the passive stance (default 0.5, 0.5): a push-off that lasts to
  take-off or past it leaves the joints extended beyond their touchdown angles when the force reaches zero, so
  the hip stands higher at take-off than at touchdown (a take-off more extended than the landing);
- ``push_weights_A_K_H``: the push-off's share per joint (default 1, 0.6, 0.3): where the push-off work goes
  (the seed's push = brake energies, its Table 1);
- ``preload_A_K``: a touchdown moment m0 (N m, ankle, knee; Eq3Law.m0, the seed's Eq. 3 integration constant
  M_s0, which the per-stance fit's intercept absorbs): the springs rest more extended than the landing angle;
- ``late_A_K_H``: session 12's variant (push-off from 0.6 for 0.8 of the passive stance, trunk balance 500 / 60)
  with the push-off's shares A, K, H per joint (e.g. 1, 0, 0.3: the take-off extension carried by the ankle);
- ``trunk_balance_K_B``: the trunk balance's stiffness and damping (default 800 N m/rad, 40 N m s/rad; e.g. a
  balance that acts more on the trunk's pitch rate, so that it holds the hip more in the faster stances);
- ``trunk_rising_K``: touchdown hip flexed 0.10 rad more (trunk leaning further forward) with the trunk balance
  K N m/rad referenced to the candidate's touchdown trunk angle, so the trunk rises on the hip in stance.

Per variant and frequency, one noise-free 5-hop trial (seed 1), its third stance, from the simulator's own state
(not the analysis; bench/simulator_issue17.py measures through the analysis): stance, peak GRF, the hip joint
centre's range in stance and its take-off minus touchdown height, the body COM's drop, their ratio, the ranges of
flexion (maximal minus touchdown), and per joint the negative work (brake) and the push-off's work. The hip joint
centre's range is 5-6 points of percent above the analysis' hip-marker excursion (base: -15 / -26 / -32 % here,
-20 / -31 / -37 % in bench/simulator_issue17.py).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from simulator_issue17 import LAW_SCALES  # noqa: E402  (benches next to this one)
from simulator_realism import SEED_TABLE1  # noqa: E402

from hop_impedance.simulation.dynamics import body_com, joint_positions  # noqa: E402
from hop_impedance.simulation.hopping_trial import (  # noqa: E402
    HoppingConfig,
    push_off_part,
    simulate_hopping,
    touchdown_posture,
)
from hop_impedance.simulation.impedance_laws import CompositeLaw, Eq3Law, PushOff, TrunkBalance  # noqa: E402
from hop_impedance.simulation.scenarios import (  # noqa: E402
    PUSH_OFF_BASE_NM,
    SEED_LIKE_TOUCHDOWN_RHO,
    hopping_config,
    seed_like_options,
    shoe_pad,
)

VARIANTS = ("base", "push_0.6_0.6", "push_0.6_0.8", "push_0.7_1.0", "push_weights_1_1.2_0.3",
            "push_weights_1_0.6_0", "preload_20_10", "preload_40_20", "trunk_rising_800", "trunk_rising_400")


def candidate_options() -> dict:
    """Session 11's rigid-plate candidate (bench/simulator_issue17.py --bell 0.9 --law-scale bell09_rigid_pad15_3
    --surface rigid --pad 15,3)."""
    return {**seed_like_options(), "bell_activation_min": 0.9, "law_scale": LAW_SCALES["bell09_rigid_pad15_3"],
            "pad": shoe_pad(0.015, 3.0)}


def variant_config(name: str, freq_hz: float):
    """(chain, HoppingConfig) of a named variant at ``freq_hz`` (module docstring)."""
    options = candidate_options()
    kind = name.split("_")[0]
    values = [float(v) for v in name.split("_") if v.lstrip("-").replace(".", "", 1).isdigit()]
    if name.startswith("push_weights_"):
        pass  # the push-off part is replaced below
    elif kind == "late":
        options["push_timing"], options["trunk_balance"] = (0.6, 0.8), TrunkBalance(500.0, 60.0)
    elif kind == "push":
        options["push_timing"] = tuple(values)
    elif name.startswith("trunk_balance_"):
        options["trunk_balance"] = TrunkBalance(values[0], values[1])
    elif kind == "trunk":
        chain, _ = hopping_config(freq_hz, "rigid", 1, variability=False, **options)
        reference = float(touchdown_posture(chain, np.array(SEED_LIKE_TOUCHDOWN_RHO))[3])
        ankle, knee, hip = SEED_LIKE_TOUCHDOWN_RHO
        options["touchdown_rho_rad"] = (ankle, knee, hip + 0.10)
        options["trunk_balance"] = TrunkBalance(values[-1], 40.0, reference)
    chain, cfg = hopping_config(freq_hz, "rigid", 5, variability=False, **options)
    law = cfg.law
    assert isinstance(law, CompositeLaw)  # hopping_config's law: Eq. 3 and the push-off
    if name.startswith("push_weights_") or kind == "late":
        push = push_off_part(law)
        assert push is not None
        law = law.replace_part(push, PushOff(PUSH_OFF_BASE_NM * np.array(values), push.onset_s, push.duration_s))
    elif kind == "preload":
        eq3 = law.part(Eq3Law)
        law = law.replace_part(eq3, replace(eq3, m0=np.array([values[0], values[1], 0.0])))
    return chain, HoppingConfig(**{**cfg.__dict__, "law": law})


def measure(name: str, freq_hz: float) -> str:
    """One table row: the variant's third stance at ``freq_hz`` against seed Table 1."""
    seed = SEED_TABLE1[freq_hz]
    try:
        chain, cfg = variant_config(name, freq_hz)
        trial = simulate_hopping(chain, cfg, seed=1)
    except ValueError as exc:
        return f"| {name} | {freq_hz:g} | no hop: {exc} |" + " |" * 10
    if len(trial.stances) < 3:
        return f"| {name} | {freq_hz:g} | stopped: {trial.stop_reason} |" + " |" * 10
    rec = trial.stances[2]
    st = rec.stance
    hip = joint_positions(chain, st.g)[:, 3, 1]
    com = body_com(chain, st.g)[:, 1]
    excursion, drop = hip.max() - hip.min(), com[0] - com.min()
    rom = st.rho_rad.max(axis=0) - st.rho_rad[0]
    power = -st.moments_nm * st.omega_rad_s  # joint power, W (extensor moment positive, flexion positive)
    brake = -np.trapezoid(np.minimum(power, 0.0), st.t_s, axis=0)
    push = push_off_part(rec.law)
    push_w = (np.trapezoid(-push.profile(st.t_s)[:, None] * push.amplitude_nm * st.omega_rad_s, st.t_s, axis=0)
              if push is not None else np.zeros(3))
    bw = chain.total_mass_kg * chain.gravity_m_s2
    grf = st.grf_n[:, 1].max() / bw

    def dev(sim: float, ref: float) -> str:
        return f"{100 * (sim / ref - 1):+.0f} %"

    return (f"| {name} | {freq_hz:g} | {1000 * st.duration_s:.0f} ({dev(1000 * st.duration_s, seed['stance_ms'])}) | "
            f"{grf:.2f} ({dev(grf, seed['grf_bw'])}) | {excursion:.3f} ({dev(excursion, seed['hip_exc_m'])}) | "
            f"{1000 * (hip[-1] - hip[0]):+.1f} | {drop:.3f} | {excursion / drop:.2f} | "
            + " / ".join(f"{r:.2f} ({dev(r, s)})" for r, s in zip(rom, seed["rom"])) + " | "
            + " / ".join(f"{b:.1f}" for b in brake) + " | " + " / ".join(f"{w:.1f}" for w in push_w) + " | "
            f"{st.g[-1, 5] - st.g[0, 5]:+.3f} | "
            + " / ".join(f"{d:+.3f}" for d in st.rho_rad[-1] - st.rho_rad[0]) + " |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", default=",".join(VARIANTS), help="comma-separated names (module docstring)")
    parser.add_argument("--freqs", default="1.53,1.87,2.2", help="a subset of 1.53,1.87,2.2")
    args = parser.parse_args()
    freqs = [f for f in SEED_TABLE1 if f in {float(v) for v in args.freqs.split(",")}]
    print("| variant | f (Hz) | stance ms (vs seed) | peak GRF BW | hip joint range in stance m | hip take-off minus "
          "touchdown mm | COM drop m | hip range / COM drop | range of flexion ankle / knee / hip rad | brake J "
          "ankle / knee / hip | push-off work J | trunk pitch take-off minus touchdown rad | "
          "joint angles take-off minus touchdown, ankle / knee / hip rad (flexion +) |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|", flush=True)
    t0 = time.perf_counter()
    for name in args.variants.split(","):
        for f in freqs:
            print(measure(name, f), flush=True)
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
