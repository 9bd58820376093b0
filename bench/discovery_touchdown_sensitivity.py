"""Where the true law's stance-duration error comes from on our simulator's noise-free null (issue 16, session 17).

Our stance-set generator (:func:`hop_impedance.simulation.stance_set.simulate_stance_set_recording`) simulates each
stance from a drawn touchdown state (the segments at rest, the body falling at the touchdown speed) on
:data:`~hop_impedance.simulation.stance_set.RIGID_NO_BOUNCE`. Here every stance of its noise-free null is simulated
again with the generating law, on the generator's body or the one discovery measures, from the generator's own
touchdown state or the one discovery measures (``MeasuredStance.touchdown``, the low-passed kinematics at the first
plate sample after the detected touchdown), and from the generator's state with only its posture or only its
velocities replaced by the measured ones, and from the state session 14's option extrapolates from the flight's markers
(``measurement.TOUCHDOWN_FROM_FLIGHT``, not the default). Printed per stance: the simulated stance time minus the
measured one (ms).

The law here is the generator's (touchdown moment 0 at the contact), not the ``M_td`` a candidate estimates, so this
separates the body and the state from the law's reference; ``bench/discovery_stance_edges.py`` gives the
candidate-like figures.

Usage: .venv/bin/python bench/discovery_touchdown_sensitivity.py [--freq 1.53] [--seed 0] [--hops 8]
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from functools import partial

import numpy as np

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.discovery import measurement
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.simulation import stance_set as sset
from hop_impedance.simulation.dynamics import chain_from_body_model
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, Effects
from hop_impedance.simulation.sensors import SensorConfig, noise_free
from hop_impedance.simulation.stance import simulate_stance

NULL = Effects(angle_dependent_stiffness=False, damping=False, push_off=False)


def generator_touchdowns(chain, freq_hz: float, seed: int, hops: int):
    """The generator's law and touchdown states, drawn as ``simulate_stance_set_recording`` draws them (same rng)."""
    law, speed_nom, _ = sset._stance_set_law(chain, freq_hz, NULL, None, sset.RIGID_NO_BOUNCE, DEFAULT_TOUCHDOWN_RHO)
    rng = np.random.default_rng(seed)
    draw = partial(sset._draw_touchdown, chain, rng, DEFAULT_TOUCHDOWN_RHO, 0.02, speed_nom, 0.05)
    return law, [draw() for _ in range(hops)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--freq", type=float, default=1.53)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--hops", type=int, default=8)
    args = ap.parse_args()
    rec, truth = sset.simulate_stance_set_recording(args.freq, ("rigid",), args.hops, args.seed, NULL,
                                                    noise_free(SensorConfig()))
    trial = measure_trial(rec)
    measurement.TOUCHDOWN_FROM_FLIGHT = True
    from_flight = {s.index: s.touchdown for s in measure_trial(rec).stances}
    measurement.TOUCHDOWN_FROM_FLIGHT = False
    gen_chain = chain_from_body_model(body_model_from_stature(sset.SEED_SUBJECT))
    law, tds = generator_touchdowns(gen_chain, args.freq, args.seed, args.hops)
    assert truth["redrawn_hops"] == 0, "a re-drawn hop changes the rng's sequence"

    def stance_time(chain, td) -> float:
        st = simulate_stance(chain, law, sset.RIGID_NO_BOUNCE, td, t_max_s=2.0 / args.freq, rtol=1e-7, atol=1e-9)
        return st.duration_s if st.end_reason == "take_off" else np.nan

    cols = ("generator's body and state", "measured body, generator's state", "generator's body, measured state",
            "measured posture, generator's velocities", "generator's posture, measured velocities",
            "generator's body, state from the flight")
    rows = []
    t0 = (rec.start_ns - noise_free(SensorConfig()).start_ns) * 1e-9
    for s in trial.stances:
        k = int(np.argmin([abs(st["touchdown_s"] - t0 - s.touchdown_s) for st in truth["stances"]]))
        td, meas = tds[k], s.touchdown
        measured = s.takeoff_s - s.touchdown_s
        variants = (stance_time(gen_chain, td), stance_time(trial.chain, td), stance_time(gen_chain, meas),
                    stance_time(gen_chain, replace(td, g=meas.g)), stance_time(gen_chain, replace(td, gd=meas.gd)),
                    stance_time(gen_chain, from_flight[s.index]) if s.index in from_flight else np.nan)
        rows.append([1e3 * (v - measured) for v in variants])
        d_g, d_gd = meas.g - td.g, meas.gd - td.gd
        print(f"stance {k}: measured {1e3 * measured:.0f} ms; simulated minus measured (ms): "
              + ", ".join(f"{c} {r:+.1f}" for c, r in zip(cols, rows[-1]))
              + f"; measured minus generator's state: q1..q4 {np.round(d_g[2:], 3).tolist()} rad, toe vz {d_gd[1]:+.2f} m/s,"
              f" q rates {np.round(d_gd[2:], 2).tolist()} rad/s", flush=True)
        if s.index in from_flight:
            f_g, f_gd = from_flight[s.index].g - td.g, from_flight[s.index].gd - td.gd
            print(f"  from the flight minus generator's: q1..q4 {np.round(f_g[2:], 3).tolist()} rad, toe vz {f_gd[1]:+.2f} m/s,"
                  f" q rates {np.round(f_gd[2:], 2).tolist()} rad/s")
    r = np.array(rows)
    print(f"{args.freq} Hz, seed {args.seed}, {len(rows)} stances, simulated minus measured stance time, mean [min, max] ms"
          " (nan: no take-off):")
    for c, col in zip(cols, r.T):
        print(f"  {c}: {np.nanmean(col):+.1f} [{np.nanmin(col):+.1f}, {np.nanmax(col):+.1f}], RMS "
              f"{np.sqrt(np.nanmean(col ** 2)):.1f}, no take-off {int(np.isnan(col).sum())}")


if __name__ == "__main__":
    main()
