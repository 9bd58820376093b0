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
       .venv/bin/python bench/simulator_energy_budget.py --lossless --hopper seed-like [--hops 30] [--no-feedback]
                   [--perturb FRACTION]
       .venv/bin/python bench/simulator_energy_budget.py --find-orbits [--write] [--newton-continuation [--to HZ]]
       .venv/bin/python bench/simulator_energy_budget.py --scan-turning-points HZ [--scan-count N]
(``--write`` also writes docs/simulator_energy.md; ``--trunk K`` adds a trunk-balance moment of
stiffness K N m/rad; ``--lossless`` runs issue 17's passive test instead: no damping, no push-off,
lossless surface, per hop stance time, COM apex and energy by component, hop N against hop 3;
``--balance`` chooses how the trunk is held, ``--periodic`` adds the periodic hop and its eigenvalues,
``--landing`` starts on it and lands along its touchdown rates, ``--posture-sd`` adds touchdown noise;
``--hopper seed-like`` runs the seed-like hopper's lossless counterpart from its stored periodic hops with the
landing feedback (issue 17, session 15), ``--find-orbits`` finds them again: time-symmetric hops from stored turning
points since session 31, session 15's Newton continuation with ``--newton-continuation``.)
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
    """(chain, config) of issue 17's passive test: no damping, no push-off, lossless hard surface, no sliding
    (scenarios.lossless_hopper_config on the hard surface).

    ``seed_like``: scenarios.seed_like_options (toe-tip contact, its posture) with the trunk held by
    ``balance``: ``active`` scenarios.TRUNK_BALANCE (a moment on the trunk's pitch about its touchdown
    value), ``fixed`` the same about the nominal touchdown pitch (a reference that does not move with the
    foot placement), ``hip_spring`` a hip spring of scenarios.HIP_TRUNK_SPRING_NM_RAD (conservative).
    ``posture_sd_rad``: seeded hop-to-hop noise of the touchdown joint angles (HoppingConfig.posture_sd_rad).
    """
    from hop_impedance.simulation.hopping_trial import touchdown_posture
    from hop_impedance.simulation.scenarios import lossless_hopper_config, seed_like_options

    options = seed_like_options() if seed_like else {"trunk_balance": TrunkBalance(trunk) if trunk else None}
    chain, config = lossless_hopper_config(freq_hz, hops, options, "hard",
                                           "hip_spring" if seed_like and balance == "hip_spring" else "balance")
    config = dataclasses.replace(config, flight=flight, posture_sd_rad=posture_sd_rad)
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
    chain, config = lossless_config(freq_hz, hops, trunk, flight, seed_like, balance, posture_sd_rad)
    setup = f"seed-like options, {balance} trunk balance" if seed_like else f"trunk {trunk:g} N m/rad"
    if posture_sd_rad:
        setup += f", touchdown posture noise {posture_sd_rad:g} rad (seed {seed})"
    head = []
    if landing:
        cal = _calibration(chain, config)
        ph, text = periodic_line(chain, config, cal)
        config = dataclasses.replace(config, landing_rates_rad_s=tuple(float(r) for r in ph.state[3:]),
                                     first_touchdown=tuple(float(v) for v in ph.state), com_ahead_m=cal.com_ahead_m)
        head = [text, "  landing along its touchdown rates: " + periodic_line(chain, config, cal, ph.state)[1].strip()]
        setup += ", starting on the periodic hop and landing along its touchdown rates"
    text = trial_lines(chain, config, f"{flight}, {freq_hz} Hz, {setup}", seed)
    if periodic and not landing:
        text += "\n" + periodic_line(chain, config, None)[1]
    return "\n".join([text] + head)


def trial_lines(chain, config, title: str, seed: int = 1) -> str:
    """One lossless trial hop by hop (:func:`lossless_hops`' lines): stance, COM apex, energy by component, hop N
    against hop 3, the trunk's pitch and the hip's range, and the energy at touchdown against hop 1's."""
    from hop_impedance.simulation.dynamics import body_com, com_velocity

    try:
        trial = simulate_hopping(chain, config, seed=seed)
    except ValueError as exc:
        return f"{title}: no trial ({exc})"
    rows, parts = [], []
    lines = [f"{title}: {len(trial.stances)} hops"
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
    take_off = [e["com_to_j"] + e["segments_to_j"] + e["springs_to_j"] for e in parts]
    flight = max((abs(nxt["e_touchdown_j"] - to) / to for nxt, to in zip(parts[1:], take_off)), default=np.nan)
    lines.append(f"  E at touchdown, hop {len(parts)} - hop 1: {parts[-1]['e_touchdown_j'] - e0:+.3f} J "
                 f"(largest relative difference from hop 1: {drift:.1e}; E at touchdown against the previous take-off's "
                 f"COM + segments + springs: {flight:.1e}); "
                 f"trunk-balance work over hops 1-{len(parts) - 1}: {trunk_j:+.3f} J")
    return "\n".join(lines)


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


def stored_hop(hop, feedback, closed, found: bool) -> dict:
    """A periodic hop and its landing feedback as scenarios.SEED_LIKE_LOSSLESS_HOPS_FILE stores them."""
    return {"state": [float(v) for v in hop.state], "landing_rates_rad_s": list(feedback.landing_ref),
            "com_ahead_m": feedback.com_ahead_ref_m, "gain": [list(row) for row in feedback.gain],
            "stance_s": hop.stance_s, "flight_s": hop.flight_s, "found": found,
            "residual": float(np.abs(hop.residual).max()),
            "open_loop_moduli": [float(abs(v)) for v in hop.eigenvalues],
            "closed_loop_moduli": [float(abs(v)) for v in closed]}


def hop_summary(hop, stored: dict) -> str:
    """The printed rest of a found hop's line: residual, timing, touchdown state and eigenvalue moduli."""
    return (f"max |P(x) - x| {stored['residual']:.1e}), stance {1000 * hop.stance_s:.1f} ms, flight "
            f"{1000 * hop.flight_s:.1f} ms ({1 / (hop.stance_s + hop.flight_s):.2f} Hz), touchdown speed "
            f"{hop.state[0]:.3f} m/s, COM vx {hop.state[1]:+.3f} m/s; |eigenvalues| landing along fixed rates "
            + ", ".join(f"{v:.3f}" for v in stored["open_loop_moduli"][:4]) + "; with the landing feedback "
            + ", ".join(f"{v:.3f}" for v in stored["closed_loop_moduli"][:4]))


#: ``--find-orbits``: the law frequencies the continuation steps through from 2.2 Hz (Hz): 0.01 Hz steps below 1.95 Hz,
#: where larger steps leave the attracting hop's reach.
ORBIT_PATH = (2.2, 2.1, 2.0, 1.975, 1.95) + tuple(round(1.94 - 0.01 * k, 2) for k in range(42))
#: Hops the closed loop runs at each next law frequency before its last touchdown starts the Newton steps.
SETTLE_HOPS = 15


def find_seed_like_orbits(path=ORBIT_PATH, at_seed_frequency: bool = False, extra: dict | None = None) -> dict:
    """The periodic hops of the seed-like hopper's lossless counterpart and their landing feedback, by continuation in
    the law's frequency (scenarios.lossless_hopper_config of scenarios.seed_like_hopper_options()).

    At 2.2 Hz: the calibrated hop, the periodic hop nearest it with the energy-keeping flight's own rule (reversed
    take-off rates), then the periodic hop landing along its touchdown rates (periodic_hop.periodic_hop) and the
    feedback that makes it attract (periodic_hop.landing_feedback). Each next law frequency starts from the previous
    periodic hop with the previous feedback in the loop: :data:`SETTLE_HOPS` hops of the trial (the closed loop
    attracts where the hop without it is unstable, and where Newton steps from the previous hop stall), whose last
    touchdown, re-stated with its own landing rates and placement, starts the Newton steps of the periodic hop; that
    hop gets its own feedback. ``at_seed_frequency``: instead each periodic hop is the one whose period is 1 / its
    law's frequency (Newton steps on the closed loop with that condition, chosen along the family of periodic hops of
    other energies; found at 2.2 and 2.1 Hz, not at 2.0 Hz). Stops at the first law frequency where none is found.
    ``extra``: hopping_config options added to the preset's (``--biarticular``: a conservative knee-ankle spring,
    session 28's probe; printed only).
    Returns {frequency: dict of the hop (scenarios.SEED_LIKE_LOSSLESS_HOPS' entries) and its eigenvalues}.
    """
    from hop_impedance.simulation.hopping_trial import touchdown_state_vector
    from hop_impedance.simulation.periodic_hop import landing_feedback, periodic_hop, touchdown_vector
    from hop_impedance.simulation.scenarios import seed_like_lossless_counterpart

    chain, config = seed_like_lossless_counterpart(path[0], 30, extra)
    cal = _calibration(chain, config)
    hop = periodic_hop(chain, config, cal, touchdown_vector(cal.speed_m_s, 0.0, cal.com_ahead_m,
                                                            cal.touchdown_rates_rad_s))
    config = dataclasses.replace(config, landing_rates_rad_s=tuple(float(v) for v in hop.state[3:]))
    hop = periodic_hop(chain, config, cal, hop.state)
    feedback = None
    out = {}
    for freq in path:
        chain, config = seed_like_lossless_counterpart(freq, SETTLE_HOPS, extra)
        landing = hop.state[3:] if feedback is None else feedback.landing_ref
        config = dataclasses.replace(config, landing_rates_rad_s=tuple(float(v) for v in landing),
                                     landing_feedback=feedback)
        settled = False
        if feedback is not None and not at_seed_frequency:
            trial = simulate_hopping(chain, dataclasses.replace(config, com_ahead_m=cal.com_ahead_m,
                                                                first_touchdown=tuple(float(v) for v in hop.state)))
            settled = not trial.stop_reason
            start = touchdown_state_vector(chain, trial.stances[-1].touchdown)
        if not settled:  # the first law, a periodic hop of period 1/f, or a settling trial that stopped: Newton steps
            looped = periodic_hop(chain, config, cal, hop.state, period_s=1.0 / freq if at_seed_frequency else None)
            start, settled = looped.state, looped.success
        landing_new, ahead = (start[3:], cal.com_ahead_m) if feedback is None else feedback.choose(start)
        config = dataclasses.replace(config, landing_rates_rad_s=tuple(float(v) for v in landing_new),
                                     landing_feedback=None)
        cal = dataclasses.replace(cal, com_ahead_m=float(ahead))
        try:
            hop = periodic_hop(chain, config, cal, start, max_iterations=6)
        except ValueError as exc:
            print(f"  {freq:g} Hz: no periodic hop ({exc})", flush=True)
            break
        feedback, closed = landing_feedback(chain, config, cal, hop.state)
        out[freq] = stored_hop(hop, feedback, closed, bool(settled and hop.success))
        print(f"  {freq:g} Hz: periodic hop {'found' if out[freq]['found'] else 'NOT found'} ("
              + hop_summary(hop, out[freq]), flush=True)
        if not out[freq]["found"]:
            break
    return out


#: ``--find-orbits`` (session 31): per seed frequency's law the turning point a time-symmetric periodic hop starts
#: from (periodic_hop.symmetric_hop: joint flexions from the touchdown posture (rad), COM ahead of the toe (m), toe
#: height (m), the last held: it picks the hop's energy). How they were found (session 31, docs/simulator.md): at
#: 2.2 Hz's law from a random scan of turning points that take off (a hop of 59 ms flight, 4.3 mm of COM rise: too
#: low, so 2.2 Hz keeps session 15's hop); 1.87 Hz's by continuation from it (in the law's frequency with the take-off
#: speed held at 0.2 m/s to 1.925 Hz, then with the toe height held at -9.21 mm); the same continuation stalls near
#: 1.85 Hz (residual 1e-2, at take-off speeds 0.2-0.6 m/s); 1.53 Hz's from the 4th of 6 random turning points of
#: ``--scan-turning-points 1.53`` (residual 1.4e-4), re-solved from its guess rounded to the printed 3 decimals
#: (0.751, 0.22, 0.175, -0.018, -0.009): residual 4.9e-10.
#: Session 32 (the preset's law re-found for the energy-keeping flight): each re-solved from session 31's turning point
#: (1.53: (1.1332, 0.3400, 0.0953, -0.0201, -0.009), 1.87: (0.5810, 0.2742, 0.0766, -0.0007, -0.00921)), stored here as
#: found so that ``--find-orbits --write`` starts on them.
#: Session 33 (the trunk-still preset's law): by continuation in the law's factors from session 32's law (steps of
#: 1/8 to 1/3 of the way, each solved from the previous turning point); with the toe height held the continuation
#: stalls on a fold (1.87 Hz at 0.21 of the way, touchdown speed 0.85 m/s; residual 2e-4), so the toe height was
#: raised there (1.87: -9.21 -> -8.5 mm at 0.21 of the way, then to the end). At 1.53 Hz raising it (to -7.15 mm), or
#: holding a joint's flexion instead, stalls again at 0.76-0.80 of the way (residual 1e-4..3e-3), so 1.53 Hz's is the
#: third random turning point of ``--scan-turning-points 1.53 --scan-seed 2`` at the new law (residual 5.8e-10), as printed.
SYMMETRIC_TURNING_POINTS = {
    1.53: (1.0834, 0.4138, 0.1219, -0.0103, -0.0105),
    1.87: (0.6349146243849653, 0.29811695135088956, 0.08278064268129605, -0.0017920565023042117, -0.0085),
}


#: ``--find-orbits`` (session 33, the trunk-still preset's law): the 2.2 Hz law's touchdown state (speed, COM vx, COM
#: ahead, rates q1..q4) and foot placement reference (m) that the Newton steps start from. The calibrated hop's Newton
#: path (:func:`find_seed_like_orbits`) ends at this law on a hop of 12 ms flight; this is session 32's stored hop
#: carried by Newton steps through the law's factors (a quarter, five eighths, all of the way from session 32's law,
#: each converged to 3e-8; stance 285.0 ms, flight 123.4 ms).
NEWTON_STARTS = {
    2.2: ((0.6573478231073714, -0.11718899037897791, 0.025325818976548533, 1.594521412735398, -1.2205717888369605,
           0.5098340314317543, 0.44718521013131246), 0.0027697509686915372),
}


def hop_with_feedback(chain, config, x: np.ndarray, ahead: float):
    """The periodic hop nearest touchdown state ``x`` (foot placement reference ``ahead``) of the trial's own hop map
    landing along its touchdown rates (periodic_hop.periodic_hop) and the landing feedback that makes it attract
    (periodic_hop.landing_feedback); returns (hop, stored dict)."""
    from hop_impedance.simulation.hopping_trial import given_start_calibration
    from hop_impedance.simulation.periodic_hop import landing_feedback, periodic_hop

    config = dataclasses.replace(config, com_ahead_m=float(ahead), first_touchdown=tuple(float(v) for v in x),
                                 landing_rates_rad_s=tuple(float(v) for v in x[3:]))
    cal = given_start_calibration(config)
    hop = periodic_hop(chain, config, cal, np.asarray(x, float), own_landing=True)
    config = dataclasses.replace(config, landing_rates_rad_s=tuple(float(v) for v in hop.state[3:]))
    cal = dataclasses.replace(cal, com_ahead_m=hop.com_ahead_m)
    feedback, closed = landing_feedback(chain, config, cal, hop.state)
    return hop, stored_hop(hop, feedback, closed, bool(hop.success))


def find_newton_orbits() -> dict:
    """The periodic hops of the seed-like hopper's lossless counterpart by Newton steps from :data:`NEWTON_STARTS`
    (:func:`hop_with_feedback`). Returns {frequency: dict of the hop and its eigenvalues}."""
    from hop_impedance.simulation.scenarios import seed_like_lossless_counterpart

    out = {}
    for freq, (x, ahead) in NEWTON_STARTS.items():
        chain, config = seed_like_lossless_counterpart(freq)
        hop, out[freq] = hop_with_feedback(chain, config, np.asarray(x, float), ahead)
        print(f"  {freq:g} Hz: periodic hop from the stored start (" + hop_summary(hop, out[freq]), flush=True)
    return out


def find_symmetric_orbits() -> dict:
    """The periodic hops of the seed-like hopper's lossless counterpart from time-symmetric stances (session 31):
    per law frequency of :data:`SYMMETRIC_TURNING_POINTS` the symmetric hop (periodic_hop.symmetric_hop), checked and
    polished as a fixed point of the trial's own hop map landing along its touchdown rates (periodic_hop.periodic_hop),
    and the landing feedback that makes it attract (periodic_hop.landing_feedback).
    Returns {frequency: dict of the hop (scenarios.SEED_LIKE_LOSSLESS_HOPS' entries) and its eigenvalues}."""
    from hop_impedance.simulation.periodic_hop import symmetric_hop
    from hop_impedance.simulation.scenarios import seed_like_lossless_counterpart

    out = {}
    for freq, mid in SYMMETRIC_TURNING_POINTS.items():
        chain, config = seed_like_lossless_counterpart(freq)
        mid, x, res = symmetric_hop(chain, config, np.asarray(mid, float))
        hop, stored = hop_with_feedback(chain, config, x, float(x[2]))
        out[freq] = {**stored, "symmetric_residual": res, "turning_point": [float(v) for v in mid]}
        print(f"  {freq:g} Hz: symmetric hop (turning point residual {res:.1e}; as the trial's fixed point "
              + hop_summary(hop, out[freq]), flush=True)
    return out


def scan_turning_points(freq_hz: float, n: int, seed: int = 0) -> None:
    """``--scan-turning-points F``: ``n`` random turning points at F Hz's law that take off (flexions 0.2-0.9 /
    0.1-0.6 / 0-0.2 rad, COM -20..20 mm ahead of the toe, pad -12..-4 mm), each solved by periodic_hop.symmetric_hop;
    printed (how a law without a stored turning point is searched; session 31 at 1.53 Hz)."""
    from hop_impedance.simulation.periodic_hop import symmetric_hop, symmetric_stance
    from hop_impedance.simulation.scenarios import seed_like_lossless_counterpart

    chain, config = seed_like_lossless_counterpart(freq_hz)
    rng = np.random.default_rng(seed)
    found = 0
    while found < n:
        guess = rng.uniform([0.2, 0.1, 0.0, -0.02, -0.012], [0.9, 0.6, 0.2, 0.02, -0.004])
        try:
            if symmetric_stance(chain, config, guess).end_reason != "take_off":
                continue
        except ValueError:  # no posture with that COM offset
            continue
        found += 1
        mid, x, res = symmetric_hop(chain, config, guess)
        print(f"  {freq_hz:g} Hz, guess {np.round(guess, 3).tolist()}: turning point {np.round(mid, 4).tolist()}, "
              f"residual {res:.1e}, touchdown speed {x[0]:.3f} m/s", flush=True)


def write_orbits(found: dict, write: bool) -> None:
    """Print (and with ``write`` write) the periodic hops :func:`find_seed_like_orbits` found, at the seed frequencies."""
    import yaml

    from hop_impedance.simulation.scenarios import SEED_LIKE_LOSSLESS_HOPS_FILE, SEED_TABLE2

    kept = {f: hop for f, hop in found.items() if f in SEED_TABLE2}
    text = ("# Issue 17: periodic hops of the seed-like hopper's lossless counterpart and their landing feedback\n"
            "# (scenarios.seed_like_lossless_config). Written by `nice -n 19 .venv/bin/python "
            "bench/simulator_energy_budget.py --find-orbits --write`.\n" + yaml.safe_dump({"hops": kept}, sort_keys=True))
    if write:
        SEED_LIKE_LOSSLESS_HOPS_FILE.write_text(text, encoding="utf-8")
        print(f"wrote {SEED_LIKE_LOSSLESS_HOPS_FILE}")
    else:
        print(text)


def seed_like_lossless_lines(freq_hz: float, hops: int, feedback: bool, perturb: float, calibrated: bool = False) -> str:
    """The seed-like hopper's lossless counterpart (scenarios.seed_like_lossless_config) hop by hop (:func:`trial_lines`);
    ``calibrated``: from the calibrated hop with the energy-keeping flight's own rule instead (no stored hop)."""
    from hop_impedance.simulation.scenarios import (
        lossless_hopper_config,
        seed_like_hopper_options,
        seed_like_lossless_config,
        seed_like_lossless_hops,
    )

    if calibrated:
        chain, config = lossless_hopper_config(freq_hz, hops, seed_like_hopper_options())
        return trial_lines(chain, config, f"seed-like hopper's lossless counterpart, {freq_hz} Hz law, from the calibrated hop")
    chain, config = seed_like_lossless_config(freq_hz, hops, feedback)
    stored = seed_like_lossless_hops()[freq_hz]
    start = np.asarray(config.first_touchdown, float)
    start[[0, 3, 4, 5, 6]] *= 1.0 + perturb
    config = dataclasses.replace(config, first_touchdown=tuple(float(v) for v in start))
    moduli = stored["closed_loop_moduli" if feedback else "open_loop_moduli"]
    title = (f"seed-like hopper's lossless counterpart, {freq_hz} Hz law, stored periodic hop (stance "
             f"{1000 * stored['stance_s']:.1f} ms, flight {1000 * stored['flight_s']:.1f} ms, "
             f"{1 / (stored['stance_s'] + stored['flight_s']):.2f} Hz; |eigenvalues| "
             + ", ".join(f"{v:.3f}" for v in moduli[:4]) + ("" if feedback else ", fixed landing rule")
             + (f"), first touchdown speed and rates x {1 + perturb:g}" if perturb else ")"))
    return trial_lines(chain, config, title)


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
    parser.add_argument("--hopper", choices=("seed-like",), default=None,
                        help="with --lossless: the seed-like hopper's lossless counterpart started on its stored periodic "
                             "hop with the landing feedback (scenarios.seed_like_lossless_config; --freqs, --hops)")
    parser.add_argument("--no-feedback", action="store_true", help="with --hopper seed-like: the fixed landing rule")
    parser.add_argument("--perturb", type=float, default=0.0, metavar="FRACTION",
                        help="with --hopper seed-like: the first touchdown's speed and segment rates x (1 + FRACTION)")
    parser.add_argument("--calibrated", action="store_true",
                        help="with --hopper seed-like: start from the calibrated hop instead (no stored hop, no feedback)")
    parser.add_argument("--find-orbits", action="store_true",
                        help="find the stored periodic hops (2.2 Hz: find_newton_orbits, the lower laws: "
                             "find_symmetric_orbits); --write writes them into scenarios.SEED_LIKE_LOSSLESS_HOPS_FILE")
    parser.add_argument("--scan-turning-points", type=float, metavar="HZ",
                        help="random turning points of symmetric hops at this law frequency (scan_turning_points)")
    parser.add_argument("--scan-count", type=int, default=6, help="with --scan-turning-points: how many")
    parser.add_argument("--scan-seed", type=int, default=0, help="with --scan-turning-points: the random generator's seed")
    parser.add_argument("--newton-continuation", action="store_true",
                        help="with --find-orbits: session 15's continuation by Newton steps on the hop map from the "
                             "calibrated 2.2 Hz hop (reaches 1.93 Hz) instead of the symmetric hops (session 31)")
    parser.add_argument("--at-seed-frequency", action="store_true",
                        help="with --find-orbits: the periodic hops of period 1 / the law's frequency (printed only)")
    parser.add_argument("--to", type=float, default=ORBIT_PATH[-1], metavar="HZ",
                        help="with --find-orbits: stop the continuation at this law frequency (one of ORBIT_PATH)")
    parser.add_argument("--biarticular", metavar="K[,RA,RK]",
                        help="with --find-orbits: a conservative knee-ankle spring in the lossless counterpart "
                             "(impedance_laws.BiarticularSpring; printed only, never written)")
    args = parser.parse_args()
    if args.scan_turning_points:
        scan_turning_points(args.scan_turning_points, args.scan_count, args.scan_seed)
        return
    if args.find_orbits:
        path = ORBIT_PATH[:ORBIT_PATH.index(args.to) + 1]
        from simulator_issue17 import biarticular_spring  # a bench beside this one: the flag's one parser

        extra = {"biarticular": biarticular_spring(args.biarticular)} if args.biarticular else None
        if args.newton_continuation or args.at_seed_frequency or extra is not None:
            found = find_seed_like_orbits(path, at_seed_frequency=args.at_seed_frequency, extra=extra)
            write_orbits(found, args.write and not args.at_seed_frequency and extra is None)
        else:  # 2.2 Hz's law: Newton steps from its stored start (session 33); the lower laws: symmetric hops
            write_orbits({**find_newton_orbits(), **find_symmetric_orbits()}, args.write)
        return
    if args.lossless and args.hopper:
        for freq in (float(f) for f in args.freqs.split(",")):
            print(seed_like_lossless_lines(freq, args.hops, not args.no_feedback, args.perturb, args.calibrated),
                  flush=True)
        return
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
