"""Session 17: the body-split nuisance's landscape with and without ``identify.EQ7_FIT`` on one recording.

Per thigh/HAT fraction on a grid (``--grid``, default -0.5..0.5 step 0.05): the strict baseline identified on all
stances with that body (its hip/knee/ankle k0, and the unconstrained hip k0), and its in-sample forward gap (the
quantity ``body_nuisance.choose_body`` minimises), for EQ7_FIT off and on. Then ``choose_body`` itself, off and on.
Default recording: the second generator's strict null seed 35 (8 hops), which names a false activation with the
option on (session 16).

Usage: PYTHONPATH=<checkout> nice -n 19 .venv/bin/python bench/discovery_eq7_body_curve.py [--strict-null-seed 35]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import discovery_hit_rates as hr  # noqa: E402

from hop_impedance.discovery import body_nuisance as bn  # noqa: E402
from hop_impedance.discovery import identify as idm  # noqa: E402
from hop_impedance.discovery.forward_selection import gap_scales  # noqa: E402
from hop_impedance.discovery.measurement import measure_trial  # noqa: E402
from hop_impedance.discovery.model import ModelSpec  # noqa: E402
from hop_impedance.validation.strict_generator import strict_recording  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--strict-null-seed", type=int, default=35)
    ap.add_argument("--grid", default="")
    args = ap.parse_args()
    rec, _ = strict_recording(replace(hr.STRICT_CASES["null"], seed=args.strict_null_seed, hops=8))
    trial0 = measure_trial(rec)
    scales = gap_scales(trial0)
    grid = [float(v) for v in args.grid.split(",")] if args.grid else np.round(np.arange(-0.5, 0.501, 0.05), 3)
    print(f"strict null seed {args.strict_null_seed}: fraction | k0 ankle knee hip (unconstrained) | gap off | "
          f"k0 hip, gap on")
    for f in grid:
        t = measure_trial(rec, trial0.marker_latency_s, trial0.options, float(f), trial0.table_model)
        row = []
        for on in (False, True):
            idm.EQ7_FIT = on
            bn._CONTEXT.clear()
            _, coefs = idm.identify(ModelSpec(body_fraction=float(f)), t, t.stances)
            gap = bn.in_sample_gap(t, scales, ModelSpec(body_fraction=float(f)))
            row.append((coefs[:, 0], gap))
        print(f"  {f:+.2f} | {np.round(row[0][0], 1)} | {row[0][1]:.4f} | {row[1][0][2]:.3g}, {row[1][1]:.4f}",
              flush=True)
    for on in (False, True):
        idm.EQ7_FIT = on
        _, choice = bn.choose_body(rec, trial0)
        print(f"choose_body EQ7_FIT={on}: {choice.as_json()}")


if __name__ == "__main__":
    main()
