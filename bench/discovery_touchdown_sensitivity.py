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

``--fit-velocities W`` (a lead, not in ``discover``): the candidate-like true law (its ``M_td`` estimated as a
candidate's, ``discovery_stance_edges``) simulated from the measured posture with the touchdown *velocities* (toe vz,
q1..q4 rates) fitted per stance to the measured joint angles of the stance's first W s
(``forward_selection.velocity_window_residual``: residuals in units of 10 mrad per sample / sqrt(samples), a Gaussian
prior on the change of 0.5 m/s, 3 rad/s) by Levenberg-Marquardt to completion, and by 1 and 2 Gauss-Newton steps with
the stance's reference Jacobian (1 step: the option ``forward_selection.TOUCHDOWN_VELOCITY_FIT_S``), against the
measured velocities; printed: the simulated minus measured take-off (as the gap's duration term reads it), RMS, and
the window simulations LM took. ``--noisy``: the recording with the sensors' noise (1 mm markers, plate noise).
``--outside FILE ...``: the same on outside recordings with their truth law (``discovery_stance_edges``) instead.

``--start-after D [D ...]`` (session 22, ``forward_selection.SIMULATE_FROM_S``): the same candidate-like true law
simulated through ``forward_selection.simulate_for_gap`` from the measured touchdown state and from the measured state
D s after the touchdown (``forward_selection.late_start``), each take-off read two-sided
(``forward_selection.TWO_SIDED_DURATION``'s samples past the measured end, so a stance simulated too long counts);
printed per D: the simulated minus measured take-off RMS [min, max] (ms), the true law's mean held-out gap G, and the
measured toe velocity at the start; and, for comparison, the same from the touchdown with the velocities fitted
(``forward_selection.TOUCHDOWN_VELOCITY_FIT_S`` = 0.06, one step), read two-sided too. With ``--noisy`` /
``--outside`` as above. ``--two-segment`` (session 23, with ``--start-after``): the runs from D with
``forward_selection.TWO_SEGMENT`` (the run from the touchdown compared before the start sample; the take-off is the
late run's either way, so only G changes); ``--two-segment-flight``: ``forward_selection.TWO_SEGMENT_FLIGHT`` with
it.

Usage: .venv/bin/python bench/discovery_touchdown_sensitivity.py [--freq 1.53] [--seed 0] [--hops 8]
[--fit-velocities 0.06 | --start-after 0.02 0.04 0.06 [--two-segment]] [--noisy] [--outside FILE ...]
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery import measurement
from hop_impedance.discovery.identify import touchdown_moments
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import ModelSpec
from hop_impedance.simulation import stance_set as sset
from hop_impedance.simulation.dynamics import chain_from_body_model
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, Effects
from hop_impedance.simulation.sensors import SensorConfig, noise_free
from hop_impedance.simulation.stance import simulate_stance

sys.path.insert(0, str(Path(__file__).resolve().parent))
from discovery_truth_gap import fitted_law, outside_truth  # noqa: E402
from two_segment_flags import add_two_segment_arguments, check_two_segment  # noqa: E402

NULL = Effects(angle_dependent_stiffness=False, damping=False, push_off=False)
def fitted_velocities(chain, law, ground, s) -> tuple:
    """(touchdown state with the velocities fitted to completion by Levenberg-Marquardt on ``law``'s own window
    residual, ``forward_selection.velocity_window_residual``; simulations it took)."""
    count = [0]

    def resid(d):
        count[0] += 1
        return fs.velocity_window_residual(chain, law, ground, s, d)

    sol = least_squares(resid, np.zeros(5), method="lm", diff_step=1e-3, max_nfev=60)
    return fs._with_velocity_change(s, sol.x), count[0]


def gauss_newton_velocities(chain, law, ground, s, steps: int):
    """The touchdown state after ``steps`` Gauss-Newton steps with the stance's reference Jacobian (1 step:
    ``forward_selection.touchdown_for_gap``)."""
    jac = fs.reference_velocity_jacobian(chain, s)
    d = np.zeros(5)
    for _ in range(steps):
        d = d - np.linalg.lstsq(jac, fs.velocity_window_residual(chain, law, ground, s, d), rcond=None)[0]
    return fs._with_velocity_change(s, d)


def take_off_errors(trial, laws, grounds, window_s: float, label: str) -> None:
    """Print the simulated minus measured take-off from the measured and the fitted velocities (ms)."""
    fs.TOUCHDOWN_VELOCITY_FIT_S = window_s
    level = fs.take_off_level_n(trial)
    t0, sims = time.perf_counter(), 0
    errs = []
    for s, law, ground in zip(trial.stances, laws, grounds):
        measured = float(s.takeoff_s - s.touchdown_s)
        fitted, n = fitted_velocities(trial.chain, law, ground, s)
        sims += n
        gn = [gauss_newton_velocities(trial.chain, law, ground, s, k) for k in (1, 2)]
        row = []
        for td in (s.touchdown, fitted, *gn):
            sim = simulate_stance(trial.chain, law, ground, td, t_max_s=1.5 * float(s.t_s[-1]) + 0.05, rtol=fs.RTOL,
                                  atol=fs.ATOL, sample_times_s=s.t_s)  # the state as given
            row.append(1e3 * (fs.simulated_take_off_s(sim, s, level) - measured))
        errs.append(row)
    e = np.array(errs)
    rms = np.sqrt(np.mean(e**2, axis=0))
    print(f"{label}: true law's take-off error, measured velocities RMS {rms[0]:.1f} ms [{e[:, 0].min():+.1f}, "
          f"{e[:, 0].max():+.1f}], fitted over the first {1e3 * window_s:.0f} ms RMS {rms[1]:.1f} ms "
          f"[{e[:, 1].min():+.1f}, {e[:, 1].max():+.1f}]; {sims} window simulations, {time.perf_counter() - t0:.1f} s; "
          f"with the stance's reference Jacobian (6 window simulations per stance) and 1 / 2 Gauss-Newton steps of "
          f"the law's own (1 / 2 window simulations per stance and law): RMS {rms[2]:.1f} / {rms[3]:.1f} ms",
          flush=True)


def late_start_errors(trial, laws, grounds, deltas: list[float], label: str, two_segment: bool = False) -> None:
    """Print the true law's simulated minus measured take-off (two-sided) and mean gap from the measured touchdown
    state and from the measured state ``delta`` s after it (``forward_selection.SIMULATE_FROM_S``; with
    ``two_segment`` and ``forward_selection.TWO_SEGMENT``), per ``delta``."""
    level, scales = fs.take_off_level_n(trial), fs.gap_scales(trial)
    t0 = time.perf_counter()
    fs.TWO_SIDED_DURATION = True
    for delta in (None, "fit", *deltas):
        fs.TOUCHDOWN_VELOCITY_FIT_S = 0.06 if delta == "fit" else None
        fs.SIMULATE_FROM_S = None if delta in (None, "fit") else delta
        fs.TWO_SEGMENT = two_segment and fs.SIMULATE_FROM_S is not None
        errs, gaps, vz = [], [], []
        for s, law, ground in zip(trial.stances, laws, grounds):
            measured = float(s.takeoff_s - s.touchdown_s)
            late = fs.SIMULATE_FROM_S is not None
            vz.append(fs.late_start(trial.chain, law, ground, s).state.gd[1] if late else s.touchdown.gd[1])
            try:
                sim = fs.simulate_for_gap(trial.chain, law, ground, s)
            except RuntimeError:
                errs.append(np.nan)
                gaps.append(np.inf)
                continue
            errs.append(1e3 * (fs.simulated_take_off_s(sim, s, level) - measured))
            gaps.append(fs._gap_of(sim, s, 0.0, scales, level)["gap"])
        e = np.array(errs)
        where = {None: "touchdown", "fit": "touchdown, velocities fitted on 60 ms (1 step)"}.get(delta) or \
            f"{1e3 * delta:.0f} ms{' (two segments' if fs.TWO_SEGMENT else ''}" \
            f"{', flight' if fs.TWO_SEGMENT and fs.TWO_SEGMENT_FLIGHT else ''}{')' if fs.TWO_SEGMENT else ''}"
        print(f"{label}: from {where}: take-off error RMS {np.sqrt(np.nanmean(e**2)):.1f} ms [{np.nanmin(e):+.1f}, "
              f"{np.nanmax(e):+.1f}], failed {int(np.isnan(e).sum())}; true law's mean G {np.mean(gaps):.4f} "
              f"[{np.min(gaps):.4f}, {np.max(gaps):.4f}]; measured toe vz at the start {np.mean(vz):+.3f} m/s "
              f"[{np.min(vz):+.3f}, {np.max(vz):+.3f}]; per stance (ms) {np.round(e, 1).tolist()}", flush=True)
    fs.SIMULATE_FROM_S, fs.TWO_SIDED_DURATION, fs.TOUCHDOWN_VELOCITY_FIT_S, fs.TWO_SEGMENT = None, False, None, False
    print(f"  ({len(trial.stances)} stances, {time.perf_counter() - t0:.1f} s)", flush=True)


def outside_fit(path: Path, window_s: float | None, deltas: list[float] | None = None,
                two_segment: bool = False) -> None:
    """:func:`take_off_errors` (or with ``deltas`` :func:`late_start_errors`) on an outside recording with its truth
    law (``discovery_truth_gap.outside_truth``)."""
    _, _, trial, _, laws, grounds, _ = outside_truth(path, "estimated")
    if deltas:
        late_start_errors(trial, laws, grounds, deltas, path.stem, two_segment)
    else:
        take_off_errors(trial, laws, grounds, window_s, path.stem)


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
    ap.add_argument("--fit-velocities", type=float, default=None, metavar="W",
                    help="the touchdown velocities fitted to the first W s (see the module docstring)")
    ap.add_argument("--start-after", type=float, nargs="+", default=None, metavar="D",
                    help="also from the measured state D s after the touchdown (see the module docstring)")
    add_two_segment_arguments(ap, "--start-after")
    ap.add_argument("--noisy", action="store_true", help="with the sensors' noise (with --fit-velocities/--start-after)")
    ap.add_argument("--outside", nargs="*", default=None,
                    help="outside recordings instead (with --fit-velocities/--start-after)")
    args = ap.parse_args()
    check_two_segment(ap, args, "--start-after", bool(args.start_after))
    if args.fit_velocities is not None or args.start_after:
        if args.outside is not None:
            for f in args.outside:
                outside_fit(Path(f), args.fit_velocities, args.start_after, args.two_segment)
            return
        sensors = SensorConfig() if args.noisy else noise_free(SensorConfig())
        rec, _ = sset.simulate_stance_set_recording(args.freq, ("rigid",), args.hops, args.seed, NULL, sensors)
        trial = measure_trial(rec)
        law, _, _ = sset._stance_set_law(trial.chain, args.freq, NULL, None, sset.RIGID_NO_BOUNCE, DEFAULT_TOUCHDOWN_RHO)
        k0 = np.array(law.parts[0].k0, float)[:, None]
        laws = [fitted_law("estimated", ModelSpec(), k0, touchdown_moments(ModelSpec(), k0, s), s) for s in trial.stances]
        label = f"our simulator's null, {args.freq} Hz, seed {args.seed}{', noisy' if args.noisy else ''}"
        if args.start_after:
            late_start_errors(trial, laws, [sset.RIGID_NO_BOUNCE] * len(laws), args.start_after, label,
                              args.two_segment)
        else:
            take_off_errors(trial, laws, [sset.RIGID_NO_BOUNCE] * len(laws), args.fit_velocities, label)
        return
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
