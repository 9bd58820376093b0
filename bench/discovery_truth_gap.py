"""Forward gap of the TRUE law of outside recordings, simulated exactly like a discovery candidate.

For each truth-labelled outside recording (``../shared/foreign``) the generator's per-hop law (``kc``, ``k1``,
``k3`` in the speed form, bell activation on the stiffness, push-off with its per-hop amplitude, ``b0``, the
per-hop surface) is written as a :class:`hop_impedance.discovery.model.FittedLaw` and every measured stance is
simulated from its measured touchdown state (:func:`hop_impedance.discovery.forward_selection.law_gaps`). Printed
beside it: the gap of the baseline identified on all stances and simulated on the discovery's own rigid ground
(in-sample, so a lower bound of its held-out gap),
and with ``--discover`` the held-out final gap of ``hop-impedance discover`` and its ratio to the truth's (issue 16:
within 1.2x). A truth gap above the baseline's means our simulator and body model cannot show that effect by
forward simulation, whatever the selection does (measured on ``rate_dependent_stiffness_1301``).

Usage: .venv/bin/python bench/discovery_truth_gap.py [DIR] [CASE ...] [--discover]
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from hop_impedance.discovery.forward import ground_of
from hop_impedance.discovery.forward_selection import law_gaps
from hop_impedance.discovery.identify import identify, touchdown_moments
from hop_impedance.discovery.measurement import measure_trial
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
        cols += [list(law["k1"]), [0.0] * 3]
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default="../shared/foreign")
    ap.add_argument("cases", nargs="*")
    ap.add_argument("--discover", action="store_true", help="also run discover and print final gap / truth gap")
    args = ap.parse_args()
    folder = Path(args.folder)
    cases = args.cases or sorted(p.name[:-5] for p in folder.glob("*.mcap"))
    for case in cases:
        rec = load_recording(folder / f"{case}.mcap")
        truth = json.loads((folder / f"{case}.truth.json").read_text())
        latency = 0.0
        if "stream_latency" in truth["effects"]:  # "marker content lags its stamps by 20.5 ms"
            latency = 1e-3 * float(truth["effect_details"]["stream_latency"].split()[-2])
        trial = measure_trial(rec, marker_latency_s=latency)
        laws, grounds = [], []
        for s in trial.stances:
            hop = min(truth["per_hop"], key=lambda h: abs(h["t_td"] - s.touchdown_s))
            spec, coefs = truth_law(hop)
            laws.append(FittedLaw(spec, coefs, np.asarray(hop["law"]["M_td"], float)))
            grounds.append(SURFACES[hop["surface"]] if "surface_compliance" in truth["effects"] else STRICT_GROUND)
        offset = 0.0
        if "force_plate_offset" in truth["effects"]:  # "constant +25.5 N added to force.z"
            offset = float(truth["effect_details"]["force_plate_offset"].split()[1])
        g_truth = law_gaps(trial, laws, grounds, offset)
        base, c0 = identify(ModelSpec(), trial, trial.stances)
        g_base = law_gaps(trial, [FittedLaw(base, c0, touchdown_moments(base, c0, s)) for s in trial.stances],
                          [ground_of(base, s) for s in trial.stances])
        line = (f"{case}: truth-law gap {np.mean(g_truth):.4f} (finite {np.isfinite(g_truth).sum()}/{g_truth.size}), "
                f"baseline in-sample gap {np.mean(g_base):.4f}")
        if args.discover:
            doc = discover(rec)
            final = doc["final_gap"]["total"]
            line += f"; discover {doc['effects_found']} final held-out gap {final:.4f} = {final / np.mean(g_truth):.2f}x truth"
        print(line, flush=True)


if __name__ == "__main__":
    main()
