"""Where the simulated hopper's energy goes, hop by hop (issues 4 and 17: why the push-off is as large as it is).

For each hop of a noise-free hard-surface trial with the default law (seed
Table 2 k0, k1; b0 = 0.5 N m s/rad; push-off), mechanical energy E = kinetic +
gravitational of the four segments (J); the terms are those of
:mod:`hop_impedance.simulation.energy_budget` (also written per hop into every truth file):

- ``push-off``   work of the active push-off moment on the body, int -M_push omega dt;
- ``damping``    energy the Eq. 3 law dissipates (its work minus the springs left);
- ``springs``    elastic energy left in the joint springs at take-off about the touchdown
  reference; the prescribed flight does not return it;
- ``ground``     work of the surface on the foot (the hard law dissipates through its damping);
- ``trunk``      work of the trunk-balance moment at the hip (0 without one);
- ``flight``     E(next touchdown) - E(take-off) (+ springs returned, energy-keeping flight): the
  prescribed flight (``HoppingConfig.flight``, hopping_trial.py docstring) keeps the COM ballistic
  but brings the segments to rest, so the kinetic energy of segment motion relative to the COM at
  take-off is discarded; the energy-keeping flight keeps it (0 to rounding).

Check: E(take-off) - E(touchdown) = sum of the works; the largest residual is printed.

Push-off timing is printed as fractions of the actual stance: onset, peak and
end of the sin^2 pulse, and the instant of maximal ankle flexion.

Usage: .venv/bin/python bench/simulator_energy_budget.py [--hops 5] [--freqs 1.53,1.87,2.2]
       [--flights prescribed,energy_keeping] [--trunk K] [--write]
       [--lossless [--seed-like [--balance active|fixed|hip_spring]] [--periodic] [--landing]
                   [--posture-sd RAD --seeds 1,2,3]]
(``--write`` also writes docs/simulator_energy.md; ``--trunk K`` adds a trunk-balance moment of
stiffness K N m/rad; ``--lossless`` runs issue 17's passive test instead: no damping, no push-off,
lossless surface, per hop stance time, COM apex and energy by component, hop N against hop 3;
``--balance`` chooses how the trunk is held, ``--periodic`` adds the periodic hop and its eigenvalues,
``--landing`` starts on it and lands along its touchdown rates, ``--posture-sd`` adds touchdown noise.)
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from hop_impedance.simulation.energy_budget import trial_energy_budget
from hop_impedance.simulation.hopping_trial import push_off_part, simulate_hopping
from hop_impedance.simulation.impedance_laws import TrunkBalance
from hop_impedance.simulation.scenarios import hopping_config

ROOT = Path(__file__).resolve().parents[1]


def timing(rec) -> dict:
    """Push-off onset / peak / end and the instant of maximal ankle flexion, as fractions of the stance."""
    st, push = rec.stance, push_off_part(rec.law)
    duration = st.duration_s
    out = {"ankle_max_flexion": float(st.t_s[np.argmax(st.rho_rad[:, 0])] / duration)}
    out.update({"push_onset": push.onset_s / duration if push else np.nan,
                "push_peak": (push.onset_s + push.duration_s / 2) / duration if push else np.nan,
                "push_end": (push.onset_s + push.duration_s) / duration if push else np.nan})
    return out


def trial_budget(freq_hz: float, hops: int, flight: str = "prescribed", trunk: float = 0.0, seed: int = 1):
    """Per-hop budgets (the last hop has no flight term, so it is left out) and the trial's stop reason."""
    chain, config = hopping_config(freq_hz, "hard", hops)
    config = dataclasses.replace(config, flight=flight, trunk_balance=TrunkBalance(trunk) if trunk else None)
    trial = simulate_hopping(chain, config, seed=seed)
    rows = [{**b, **timing(rec)} for b, rec in zip(trial_energy_budget(trial), trial.stances)]
    return [r for r in rows if "flight_j" in r], trial.stop_reason


#: ``--balance`` choices of the lossless trial with ``--seed-like`` (how the trunk is held).
BALANCES = ("active", "fixed", "hip_spring")


def lossless_config(freq_hz: float, hops: int, trunk: float, flight: str, seed_like: bool = False,
                    balance: str = "active", posture_sd_rad: float = 0.0):
    """(chain, config) of issue 17's passive test: no damping, no push-off, lossless hard surface, no sliding.

    ``seed_like``: scenarios.seed_like_options (toe-tip contact, its posture) with the trunk held by
    ``balance``: ``active`` scenarios.TRUNK_BALANCE (a moment on the trunk's pitch about its touchdown
    value), ``fixed`` the same about the nominal touchdown pitch (a reference that does not move with the
    foot placement), ``hip_spring`` a hip spring of scenarios.HIP_TRUNK_SPRING_NM_RAD (conservative).
    ``posture_sd_rad``: seeded hop-to-hop noise of the touchdown joint angles (HoppingConfig.posture_sd_rad).
    """
    from hop_impedance.simulation.ground import HARD, lossless
    from hop_impedance.simulation.hopping_trial import touchdown_posture
    from hop_impedance.simulation.scenarios import HIP_TRUNK_SPRING_NM_RAD, Effects, seed_like_options

    options = {"trunk_balance": TrunkBalance(trunk) if trunk else None}
    if seed_like:
        options = {k: v for k, v in seed_like_options().items() if k not in ("push_timing", "bell_activation_min")}
        if balance == "hip_spring":
            options = {**options, "trunk_balance": None, "hip_trunk_spring_nm_rad": HIP_TRUNK_SPRING_NM_RAD}
    chain, config = hopping_config(freq_hz, "hard", hops, Effects(damping=False, push_off=False), variability=False,
                                   flight=flight, **options)
    config = dataclasses.replace(config, surface=lossless(HARD), friction_coefficient=None,
                                 posture_sd_rad=posture_sd_rad)
    if seed_like and balance == "fixed":
        q4 = float(touchdown_posture(chain, np.asarray(config.touchdown_rho_rad), config.com_ahead_m)[3])
        config = dataclasses.replace(config, trunk_balance=dataclasses.replace(config.trunk_balance, reference_rad=q4))
    return chain, config


def hop_energy_parts(chain, rec) -> dict:
    """Energy of one hop by component (J): COM (translation + gravity) and segment rotation about the COM
    at touchdown and take-off, joint springs at take-off, trunk-balance work split into its spring and
    damper terms, ground work."""
    from hop_impedance.simulation.dynamics import body_com, com_velocity, internal_kinetic_energy_j
    from hop_impedance.simulation.energy_budget import DEFAULT_DT_S, stance_energy_budget
    from hop_impedance.simulation.hopping_trial import simulate_resample

    st, m, g_acc = rec.stance, chain.total_mass_kg, chain.gravity_m_s2

    def com_and_segments(g, gd):
        v = com_velocity(chain, g, gd)
        return 0.5 * m * float(v @ v) + m * g_acc * body_com(chain, g)[1], internal_kinetic_energy_j(chain, g[2:], gd[2:])

    budget = stance_energy_budget(chain, rec)
    (com_td, seg_td), (com_to, seg_to) = com_and_segments(st.g[0], st.gd[0]), com_and_segments(st.g[-1], st.gd[-1])
    spring_j = damper_j = 0.0
    tb = st.trunk_balance
    if tb is not None:
        t = np.append(np.arange(0.0, st.duration_s, DEFAULT_DT_S), st.duration_s)
        dense = simulate_resample(chain, rec, t)
        ref = rec.touchdown.g[5] if tb.reference_rad is None else tb.reference_rad
        omega_hip = dense.omega_rad_s[:, 2]
        spring_j = float(np.trapezoid(tb.stiffness_nm_rad * (dense.g[:, 5] - ref) * omega_hip, t))
        damper_j = float(np.trapezoid(tb.damping_nm_s_rad * dense.gd[:, 5] * omega_hip, t))
    return {"e_touchdown_j": budget["e_touchdown_j"], "com_td_j": com_td, "segments_td_j": seg_td, "com_to_j": com_to,
            "segments_to_j": seg_to, "springs_to_j": budget["springs_left_j"] or 0.0, "trunk_spring_j": spring_j,
            "trunk_damper_j": damper_j, "ground_j": budget["ground_j"]}


def lossless_hops(freq_hz: float, hops: int, trunk: float, flight: str, seed_like: bool = False,
                  balance: str = "active", periodic: bool = False, posture_sd_rad: float = 0.0, seed: int = 1,
                  landing: bool = False) -> str:
    """Issue 17's passive test (:func:`lossless_config`); per hop the stance time, the COM apex height of the
    following flight and the energy by component (:func:`hop_energy_parts`), and how hop ``hops`` compares
    with hop 3. ``periodic``: also the periodic hop nearest the calibrated one and its eigenvalues.
    ``landing``: first find that periodic hop, then start the trial on it (HoppingConfig.first_touchdown)
    and land every hop along its touchdown rates (HoppingConfig.landing_rates_rad_s); that orbit's
    eigenvalues are reported too."""
    from hop_impedance.simulation.dynamics import body_com, com_velocity

    chain, config = lossless_config(freq_hz, hops, trunk, flight, seed_like, balance, posture_sd_rad)
    setup = f"seed-like options, {balance} trunk balance" if seed_like else f"trunk {trunk:g} N m/rad"
    if posture_sd_rad:
        setup += f", touchdown posture noise {posture_sd_rad:g} rad (seed {seed})"
    head = []
    if landing:
        cal = _calibration(chain, config)
        ph, text = periodic_line(chain, config, cal)
        config = dataclasses.replace(config, landing_rates_rad_s=tuple(float(r) for r in ph.state[3:]),
                                     first_touchdown=tuple(float(v) for v in ph.state))
        head = [text, "  landing along its touchdown rates: " + periodic_line(chain, config, cal, ph.state)[1].strip()]
        setup += ", starting on the periodic hop and landing along its touchdown rates"
    try:
        trial = simulate_hopping(chain, config, seed=seed)
    except ValueError as exc:
        return f"{flight}, {freq_hz} Hz, {setup}: no trial ({exc})"
    rows, parts = [], []
    lines = [f"{flight}, {freq_hz} Hz, {setup}: {len(trial.stances)} hops"
             + (f" (stopped: {trial.stop_reason})" if trial.stop_reason else ""),
             "  energy (J): E at touchdown; COM (translation + gravity) and segment rotation about the COM at "
             "touchdown -> take-off; joint springs at take-off; trunk-balance work, spring / damper term; ground"]
    for rec in trial.stances:
        g, gd = rec.stance.g[-1], rec.stance.gd[-1]
        vz = com_velocity(chain, g, gd)[1]
        apex = body_com(chain, g)[1] + max(vz, 0.0) ** 2 / (2 * chain.gravity_m_s2)
        rows.append((rec.stance.duration_s, apex))
        e = hop_energy_parts(chain, rec)
        parts.append(e)
        lines.append(f"  hop {rec.index + 1}: stance {1000 * rec.stance.duration_s:.1f} ms, COM apex {apex:.4f} m | "
                     f"E {e['e_touchdown_j']:.2f}; COM {e['com_td_j']:.2f} -> {e['com_to_j']:.2f}, segments "
                     f"{e['segments_td_j']:.2f} -> {e['segments_to_j']:.2f}; springs {e['springs_to_j']:.2f}; trunk "
                     f"{e['trunk_spring_j']:+.2f} / {e['trunk_damper_j']:+.2f}; ground {e['ground_j']:+.3f}")
    if len(rows) >= 4:
        (ts3, a3), (tsn, an) = rows[2], rows[-1]
        lines.append(f"  hop {len(rows)} vs hop 3: stance {tsn / ts3 - 1:+.1%}, apex {an / a3 - 1:+.2%}")
    pitch = max(float(np.abs(rec.stance.g[:, 5] - rec.touchdown.g[5]).max()) for rec in trial.stances)
    hip_range = max(float(np.ptp(rec.stance.rho_rad[:, 2])) for rec in trial.stances)
    lines.append(f"  trunk pitch within {pitch:.3f} rad of its touchdown value; hip range in stance at most "
                 f"{hip_range:.3f} rad")
    trunk_j = sum(e["trunk_spring_j"] + e["trunk_damper_j"] for e in parts[:-1])
    e0 = parts[0]["e_touchdown_j"]
    drift = max(abs(e["e_touchdown_j"] - e0) for e in parts) / e0
    lines.append(f"  E at touchdown, hop {len(parts)} - hop 1: {parts[-1]['e_touchdown_j'] - e0:+.3f} J "
                 f"(largest relative difference from hop 1: {drift:.1e}); "
                 f"trunk-balance work over hops 1-{len(parts) - 1}: {trunk_j:+.3f} J")
    if periodic and not landing:
        lines.append(periodic_line(chain, config, trial.calibration)[1])
    return "\n".join(lines + head)


def _calibration(chain, config):
    from hop_impedance.simulation.hopping_trial import calibrate, touchdown_posture

    return calibrate(chain, config, touchdown_posture(chain, np.asarray(config.touchdown_rho_rad), config.com_ahead_m))


def periodic_line(chain, config, cal, guess=None):
    """(periodic hop, line): the periodic hop nearest ``guess`` (default the calibrated touchdown state;
    simulation/periodic_hop.py) and its stability."""
    from hop_impedance.simulation.periodic_hop import periodic_hop, touchdown_vector

    if cal is None:
        cal = _calibration(chain, config)
    if guess is None:
        guess = touchdown_vector(cal.speed_m_s, 0.0, cal.com_ahead_m, cal.touchdown_rates_rad_s)
    ph = periodic_hop(chain, config, cal, guess)
    state = ", ".join(f"{v:.4f}" for v in ph.state)
    moduli = ", ".join(f"{abs(v):.3f}" for v in ph.eigenvalues)
    values, vectors = np.linalg.eig(ph.jacobian)
    k = int(np.argmax(np.abs(values)))
    mode = vectors[:, k] / vectors[np.argmax(np.abs(vectors[:, k])), k]
    mode_text = ", ".join(f"{v.real:+.2f}" for v in mode)
    return ph, (f"  periodic hop ({'found' if ph.success else 'NOT found'}: max |P(x) - x| {abs(ph.residual).max():.1e}): "
            f"touchdown state [speed, vx, COM ahead, rates q1..q4] = [{state}], stance {1000 * ph.stance_s:.1f} ms, "
            f"flight {1000 * ph.flight_s:.1f} ms ({1 / (ph.stance_s + ph.flight_s):.3f} Hz); |eigenvalues| {moduli}; "
            f"largest {values[k].real:+.3f}{values[k].imag:+.3f}j along [{mode_text}] (real part)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hops", type=int, default=5)
    parser.add_argument("--freqs", default="1.53,1.87,2.2")
    parser.add_argument("--flights", default="prescribed,energy_keeping")
    parser.add_argument("--trunk", type=float, default=0.0, help="trunk-balance stiffness (N m/rad), 0 = none")
    parser.add_argument("--write", action="store_true", help="also write docs/simulator_energy.md")
    parser.add_argument("--lossless", action="store_true",
                        help="instead: the passive lossless trial (no damping, push-off or ground loss) hop by hop")
    parser.add_argument("--seed-like", action="store_true",
                        help="with --lossless: scenarios.seed_like_options (toe-tip contact, posture, trunk balance)")
    parser.add_argument("--balance", choices=BALANCES, default="active",
                        help="with --lossless --seed-like: how the trunk is held (lossless_config)")
    parser.add_argument("--posture-sd", type=float, default=0.0,
                        help="with --lossless: touchdown joint-angle noise (rad) and --seeds to run")
    parser.add_argument("--seeds", default="1", help="with --lossless: comma-separated trial seeds")
    parser.add_argument("--landing", action="store_true",
                        help="with --lossless: land along the periodic hop's touchdown rates (lossless_hops)")
    parser.add_argument("--periodic", action="store_true",
                        help="with --lossless: also find the periodic hop and its eigenvalues (simulation/periodic_hop.py)")
    args = parser.parse_args()
    if args.lossless:
        for flight in args.flights.split(","):
            for freq in (float(f) for f in args.freqs.split(",")):
                for seed in (int(v) for v in args.seeds.split(",")):
                    print(lossless_hops(freq, args.hops, args.trunk, flight, args.seed_like, args.balance, args.periodic,
                                        args.posture_sd, seed, args.landing), flush=True)
        return
    lines = ["| flight | frequency (Hz) | push-off work | damping | springs left at take-off | ground | trunk | flight | "
             "stance balance residual |", "|---|---|---|---|---|---|---|---|---|"]
    timing_lines = ["| flight | frequency (Hz) | push-off onset | push-off peak | push-off end | ankle max flexion |",
                    "|---|---|---|---|---|---|"]
    for flight in args.flights.split(","):
        for freq in (float(f) for f in args.freqs.split(",")):
            try:
                rows, stop = trial_budget(freq, args.hops, flight, args.trunk)
            except ValueError as exc:
                lines.append(f"| {flight} | {freq:.2f} | no trial: {exc} |" + " |" * 6)
                continue
            rows = rows[1:]  # the first hop starts from the calibrated state
            if not rows:
                lines.append(f"| {flight} | {freq:.2f} | stopped: {stop} |" + " |" * 6)
                continue
            mean = {k: np.mean([r[k] for r in rows]) for k in rows[0]}
            residual = max(abs(r["residual_j"]) for r in rows)
            stopped = f" (stopped: {stop})" if stop else ""
            lines.append(f"| {flight} | {freq:.2f}{stopped} | {mean['push_off_j']:.1f} J | -{mean['damping_j']:.1f} J | "
                         f"-{mean['springs_left_j']:.1f} J | {mean['ground_j']:.1f} J | {mean['trunk_balance_j']:.1f} J | "
                         f"{mean['flight_j']:.1f} J | {residual:.2f} J |")
            timing_lines.append(f"| {flight} | {freq:.2f} | {mean['push_onset']:.0%} | {mean['push_peak']:.0%} | "
                                f"{mean['push_end']:.0%} | {mean['ankle_max_flexion']:.0%} |")
    caption = (f"(mean of hops 2 to the second-last of {args.hops}; noise-free, hard surface, default law"
               f"{f', trunk balance {args.trunk:g} N m/rad' if args.trunk else ''}; fractions of the actual stance)")
    text = "\n".join(lines) + "\n\n" + "\n".join(timing_lines) + "\n\n" + caption
    print(text)
    if args.write:
        doc = ROOT / "docs" / "simulator_energy.md"
        doc.write_text("# Simulator energy budget and push-off timing\n\nProduced by "
                       "`.venv/bin/python bench/simulator_energy_budget.py --write`; the terms are defined in "
                       "that script's docstring.\n\n" + text + "\n")
        print(f"wrote {doc}")


if __name__ == "__main__":
    main()
