"""What the second generator's strict nulls hold that the baseline cannot model (issue 16, session 8).

Per strict null seed, with the analysis' table body and with the generator's own segment parameters given to
the analysis (:func:`discovery_body_nuisance.generator_overrides`): the forward gap of the TRUE law (the
generator's k0 and per-hop ``M_td``, simulated exactly like a candidate on the generator's ground,
:func:`hop_impedance.discovery.forward_selection.law_gaps`), the strict baseline identified by regression on
all stances (in-sample gap, identified k0 against the true one, RMS error of the per-stance ``M_td``), and
per joint the ID-moment error against the true law (RMS, and the slope of that error on the joint angle
change, per stance: what the regression's k0 absorbs). With ``--discover`` also ``discover`` with the
generator's own body (what is named when the body is exactly right).

    .venv/bin/python bench/discovery_strict_floor.py --seeds 1,3 [--hops 8] [--discover]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from discovery_body_nuisance import generator_overrides  # noqa: E402
from discovery_truth_gap import STRICT_GROUND  # noqa: E402

from hop_impedance.biomech.analysis import AnalysisOptions  # noqa: E402
from hop_impedance.discovery.forward import ground_of  # noqa: E402
from hop_impedance.discovery.forward_selection import law_gaps  # noqa: E402
from hop_impedance.discovery.identify import identify, touchdown_moments  # noqa: E402
from hop_impedance.discovery.measurement import measure_trial  # noqa: E402
from hop_impedance.discovery.model import FittedLaw, ModelSpec  # noqa: E402
from hop_impedance.discovery.workflow import discover  # noqa: E402
from hop_impedance.validation.strict_generator import StrictConfig, strict_recording  # noqa: E402


def _hop(truth: dict, touchdown_s: float) -> dict:
    return min(truth["per_hop"], key=lambda h: abs(h["t_td"] - touchdown_s))


def body_row(seed: int, name: str, rec, truth: dict, options: AnalysisOptions | None) -> None:
    trial = measure_trial(rec, options=options)
    hops = [_hop(truth, s.touchdown_s) for s in trial.stances]
    laws = [FittedLaw(ModelSpec(), np.array(h["k0"], float)[:, None], np.asarray(h["M_td"], float)) for h in hops]
    g_true = law_gaps(trial, laws, [STRICT_GROUND] * len(laws))
    base, c0 = identify(ModelSpec(), trial, trial.stances)
    g_base = law_gaps(trial, [FittedLaw(base, c0, touchdown_moments(base, c0, s)) for s in trial.stances],
                      [ground_of(base, s) for s in trial.stances])
    m_err = np.array([touchdown_moments(base, c0, s) - np.asarray(h["M_td"]) for s, h in zip(trial.stances, hops)])
    rms, slopes = [], []
    for s, h in zip(trial.stances, hops):
        d = s.rho_rad - s.rho_rad[0]
        err = s.moment_nm - (np.asarray(h["M_td"]) + np.asarray(h["k0"]) * d)
        rms.append(np.sqrt(np.mean(err**2, axis=0)))
        slopes.append([np.polyfit(d[:, j], err[:, j], 1)[0] for j in range(3)])
    rng = np.array([np.ptp(s.rho_rad, axis=0) for s in trial.stances])
    print(f"seed {seed} {name}: truth-law gap {np.mean(g_true):.4f}, baseline in-sample {np.mean(g_base):.4f}; "
          f"k0 identified {np.round(c0[:, 0])} true {np.round(hops[0]['k0'])} N m/rad; M_td error RMS "
          f"{np.round(np.sqrt(np.mean(m_err**2, axis=0)), 1)} N m; ID-moment error RMS {np.round(np.mean(rms, axis=0), 1)} "
          f"N m, its slope on the angle change per stance (ankle/knee/hip) min..max "
          f"{np.round(np.min(slopes, axis=0))}..{np.round(np.max(slopes, axis=0))} N m/rad; joint range in stance "
          f"{np.round(rng.min(axis=0), 2)}..{np.round(rng.max(axis=0), 2)} rad", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,3,7,17,32,39,43,47")
    ap.add_argument("--hops", type=int, default=8)
    ap.add_argument("--discover", action="store_true", help="also discover with the generator's own body")
    args = ap.parse_args()
    for seed in (int(s) for s in args.seeds.split(",") if s):
        cfg = StrictConfig(seed=seed, hops=args.hops)
        rec, truth = strict_recording(cfg)
        own = AnalysisOptions(overrides=generator_overrides(cfg))
        body_row(seed, "table body", rec, truth, None)
        body_row(seed, "generator's body", rec, truth, own)
        if args.discover:
            doc = discover(rec, options=own)
            print(f"seed {seed} discover with the generator's body: {doc['effects_found']} "
                  f"({doc['timing']['total_s']:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
