"""Forward gap of the TRUE law of outside recordings, simulated exactly like a discovery candidate.

For each truth-labelled outside recording (``../shared/foreign``) the generator's per-hop law (``kc``, ``k1``,
``k3`` in the speed form, bell activation on the stiffness, push-off with its per-hop amplitude, ``b0``, the
per-hop surface) is written as a :class:`hop_impedance.discovery.model.FittedLaw` and every measured stance is
simulated from its measured touchdown state (:func:`hop_impedance.discovery.forward_selection.law_gaps`). Printed
beside it: the gap of the baseline identified on all stances and simulated on the discovery's own rigid ground
(in-sample, so a lower bound of its held-out gap),
and with ``--discover`` the held-out final gap of ``hop-impedance discover`` and its ratio to the truth's (issue 16:
within 1.2x), both with the regression's coefficients (``final_gap``) and identified through the simulation
(``final_gap_through_simulation``, session 17). A truth gap above the baseline's means our simulator and body
model cannot show that effect by forward simulation, whatever the selection does (measured on
``rate_dependent_stiffness_1301``).

The true law's ``M_td`` per stance: ``--touchdown-moment`` (:data:`TOUCHDOWN_MOMENTS`; default ``estimated``, as a
candidate's; sessions 2-14 used the truth's at the contact). ``--two-sided``: the gap with
``forward_selection.TWO_SIDED_DURATION``. ``--ground-damping D``: the strict ground with a damper of D N s/m (session
28: undamped, our simulated foot rings on it at 100-125 Hz, +-150 N, for the whole stance, excited at touchdown (every
toe velocity from 0 to -0.2 m/s tried on 1301); 300 N s/m damps that mode, the truth says 0).

Usage: .venv/bin/python bench/discovery_truth_gap.py [DIR] [CASE ...] [--discover] [--touchdown-moment estimated]
[--two-sided] [--ground-damping D]
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery import model
from hop_impedance.discovery.forward import ground_of
from hop_impedance.discovery.forward_selection import identification_reference, law_gaps
from hop_impedance.discovery.identify import identify, touchdown_moments
from hop_impedance.discovery.measurement import measure_trial, shift_marker_stream
from hop_impedance.discovery.model import FittedLaw, ModelSpec
from hop_impedance.discovery.workflow import discover
from hop_impedance.io.recording_io import load_recording
from hop_impedance.simulation.ground import SURFACES, GroundLaw

#: The outside generator's strict-baseline ground (its truth files' baseline note).
STRICT_GROUND = GroundLaw("stiff", 1.0e7, 1.5, 0.0)


def truth_law(hop: dict) -> tuple[ModelSpec, np.ndarray]:
    """(spec, coefficients) of one hop's truth law in the discovery's regressors."""
    law = hop["law"]
    effects, cols = [], [list(law["kc"])]
    if any(law["k1"]):
        effects.append("angle_dependent_stiffness")
        cols += [list(law["k1"])] + [[0.0] * 3] * (len(model.ANGLE_TERMS) - 1)  # Eq. 3's k2 (an option) is 0
    if any(law["k3"]):
        effects.append("rate_dependent_stiffness")
        cols.append(list(law["k3"]))  # speed form: k3 S_speed
    spec = ModelSpec(rate_form="speed")
    act = law.get("activation")
    if act:
        effects.append("time_dependent_activation")
        a0 = act["a0"]
        cols = [[c * a0 for c in col] for col in cols] + [[c * (1 - a0) for c in col] for col in cols]
        spec = replace(spec, tau_s=act["Ta_s"], activation_shape="bell", activation_form="tangent")
    if any(law["b0"]):
        effects.append("joint_damping")
        cols += [list(law["b0"]), [0.0] * 3]
    po = law.get("pushoff")
    if po:
        effects.append("active_push_off")
        spec = replace(spec, onset_s=po["t1_s"], duration_s=po["t2_s"] - po["t1_s"])
        cols.append([po["A_Nm"] * p for p in po["pattern"]])
    spec = replace(spec, effects=tuple(effects))
    return spec, np.array(cols, float).T


#: How the true law's touchdown moment ``M_td`` is set (``--touchdown-moment``; session 15). ``estimated`` (the
#: default): from the stance's ID moments with the truth's coefficients and against the identification's reference,
#: exactly as for a candidate (``identify.touchdown_moments``, ``forward_selection.identification_reference``).
#: ``first-sample``: the truth's moment at the stance's first plate sample (stance_truth, interpolated), where the
#: simulation starts. ``contact`` (sessions 2-14): the truth's ``M_td``, the moment at the true contact. The
#: simulation starts at the first plate sample after the *detected* touchdown, 1-2 ms after the true contact on the
#: outside rigid grounds, with the law's reference angles read there, so ``contact`` starts every joint
#: K * (its flexion in those 1-2 ms) too low (ankle ~190 N m/rad * 12.6 rad/s * 1.6 ms = 4 N m): most of session 14's
#: "+4.8..+10.8 ms late" on those files.
TOUCHDOWN_MOMENTS = ("estimated", "first-sample", "contact")


def true_touchdown_moment(how: str, truth: dict, hop: dict, s, start_ns: int, spec=None, coefs=None) -> np.ndarray:
    """``M_td`` (N m, shape (3,)) of one hop's true law for the simulation of stance ``s`` (:data:`TOUCHDOWN_MOMENTS`).

    ``start_ns``: the recording's first stamp (its clock against the truth's epoch).
    """
    if how == "contact":
        return np.asarray(hop["law"]["M_td"], float)
    if how == "estimated":
        return touchdown_moments(spec, coefs, s)
    return first_sample_truth(truth, hop, start_ns, s, "M")


def first_sample_truth(truth: dict, hop: dict, clock_ns: int, s, column: str) -> np.ndarray:
    """The truth's ``stance_truth`` column ``<column>_<joint>`` (ankle, knee, hip) of ``hop``, interpolated at stance
    ``s``'s first plate sample (``clock_ns``: the trial's zero), shape (3,)."""
    rows = np.asarray(truth["stance_truth"]["rows"], float)
    cols = truth["stance_truth"]["columns"]
    r = rows[rows[:, cols.index("hop")] == hop["hop"]]
    t = (clock_ns - truth["recording"]["epoch_start_ns"]) * 1e-9 + s.touchdown_s + float(s.t_s[0])
    return np.array([np.interp(t, r[:, cols.index("t_s")], r[:, cols.index(f"{column}_{j}")])
                     for j in ("ankle", "knee", "hip")])


def fitted_law(how: str, spec, coefs, m_td, s) -> FittedLaw:
    """The law with ``M_td``; with ``estimated`` also the identification's reference (as a candidate has it,
    ``forward_selection.identification_reference``), else the simulation's touchdown state's."""
    return FittedLaw(spec, coefs, m_td, identification_reference(s) if how == "estimated" else None)


def measured_outside(path: Path, options=None) -> tuple:
    """An outside recording measured as discovery measures it, the truth's marker latency removed (``options``: the
    analysis' :class:`~hop_impedance.biomech.analysis.AnalysisOptions`, default its defaults). Returns (recording,
    truth, trial, clock_ns): ``clock_ns`` is the zero of the trial's times, the first stamp once the markers are
    shifted (earlier than the recording's own ``start_ns`` when they lag)."""
    rec = load_recording(path)
    truth = json.loads(path.with_suffix(".truth.json").read_text())
    latency = 0.0
    if "stream_latency" in truth["effects"]:  # "marker content lags its stamps by 20.5 ms"
        latency = 1e-3 * float(truth["effect_details"]["stream_latency"].split()[-2])
    trial = measure_trial(rec, marker_latency_s=latency, options=options)
    return rec, truth, trial, trial_clock_ns(rec, trial)


def trial_clock_ns(rec, trial) -> int:
    """The zero of ``trial``'s times on the recording's clock: its first stamp once the markers are shifted by the
    trial's marker latency (earlier than ``rec.start_ns`` when they lag; 17 ms on the outside file 1701)."""
    return shift_marker_stream(rec, trial.marker_latency_s).start_ns


def truth_hop(truth: dict, clock_ns: int, s) -> dict:
    """The truth's hop (``per_hop`` entry) whose touchdown is nearest stance ``s``'s (``clock_ns``: the trial's zero)."""
    return min(truth["per_hop"], key=lambda h: abs((h["t_td_ns"] - clock_ns) * 1e-9 - s.touchdown_s))


def outside_truth(path: Path, touchdown_moment: str, ground_damping: float = 0.0) -> tuple:
    """An outside recording measured as discovery measures it (:func:`measured_outside`) with, per stance,
    its hop of the truth, the truth's law as a candidate would be simulated (``touchdown_moment``) and its ground.
    Returns (recording, truth, trial, hops, laws, grounds, clock_ns), ``clock_ns`` the trial's zero."""
    rec, truth, trial, clock_ns = measured_outside(path)
    strict = replace(STRICT_GROUND, damping_n_s_m=ground_damping) if ground_damping else STRICT_GROUND
    hops, laws, grounds = [], [], []
    for s in trial.stances:
        hop = truth_hop(truth, clock_ns, s)
        spec, coefs = truth_law(hop)
        m_td = true_touchdown_moment(touchdown_moment, truth, hop, s, clock_ns, spec, coefs)
        hops.append(hop)
        laws.append(fitted_law(touchdown_moment, spec, coefs, m_td, s))
        grounds.append(SURFACES[hop["surface"]] if "surface_compliance" in truth["effects"] else strict)
    return rec, truth, trial, hops, laws, grounds, clock_ns


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default="../shared/foreign")
    ap.add_argument("cases", nargs="*")
    ap.add_argument("--discover", action="store_true", help="also run discover and print final gap / truth gap")
    ap.add_argument("--touchdown-moment", choices=TOUCHDOWN_MOMENTS, default=TOUCHDOWN_MOMENTS[0])
    ap.add_argument("--two-sided", action="store_true", help="the gap with forward_selection.TWO_SIDED_DURATION")
    ap.add_argument("--ground-damping", type=float, default=0.0, help="damper of the strict ground (N s/m; truth: 0)")
    args = ap.parse_args()
    fs.TWO_SIDED_DURATION = args.two_sided
    folder = Path(args.folder)
    cases = args.cases or sorted(p.name[:-5] for p in folder.glob("*.mcap"))
    for case in cases:
        rec, truth, trial, hops, laws, grounds, _ = outside_truth(folder / f"{case}.mcap", args.touchdown_moment,
                                                                 args.ground_damping)
        offset = 0.0
        if "force_plate_offset" in truth["effects"]:  # "constant +25.5 N added to force.z"
            offset = float(truth["effect_details"]["force_plate_offset"].split()[1])
        g_truth = law_gaps(trial, laws, grounds, offset)
        base, c0 = identify(ModelSpec(), trial, trial.stances)
        g_base = law_gaps(trial, [fitted_law("estimated", base, c0, touchdown_moments(base, c0, s), s) for s in trial.stances],
                          [ground_of(base, s) for s in trial.stances])
        line = (f"{case}: truth-law gap {np.mean(g_truth):.4f} (finite {np.isfinite(g_truth).sum()}/{g_truth.size}), "
                f"baseline in-sample gap {np.mean(g_base):.4f}")
        if args.discover:
            doc = discover(rec)
            final = doc["final_gap"]["total"]
            shot = doc["final_gap_through_simulation"]["total"]
            line += (f"; discover {doc['effects_found']} final held-out gap {final:.4f} = {final / np.mean(g_truth):.2f}x "
                     f"truth, through the simulation {shot:.4f} = {shot / np.mean(g_truth):.2f}x")
        print(line, flush=True)


if __name__ == "__main__":
    main()
