"""Session 17: the body-split nuisance's landscape with and without ``identify.EQ7_FIT`` on one recording.

Per thigh/HAT fraction on a grid (``--grid``, default -0.5..0.5 step 0.05): the strict baseline identified on all
stances with that body (its hip/knee/ankle k0, and the unconstrained hip k0), and its in-sample forward gap (the
quantity ``body_nuisance.choose_body`` minimises, with the search's fit as in session 16), for EQ7_FIT off and on.
Then ``choose_body`` itself: off; on with the search's fit constrained (session 16's code); on as now (session 17:
the search's fit unconstrained).
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
    def constrained_search(spec, trial, stances, effect=None, eq7_fit=None):
        """The search's identification as before session 17's fix: EQ7_FIT's setting, whatever it asks."""
        return idm.identify(spec, trial, stances, effect)

    print(f"strict null seed {args.strict_null_seed}: fraction | k0 ankle knee hip (unconstrained) | gap off | "
          f"k0 hip, gap on")
    for f in grid:
        t = measure_trial(rec, trial0.marker_latency_s, trial0.options, float(f), trial0.table_model)
        row = []
        for on in (False, True):
            idm.EQ7_FIT = on
            bn._CONTEXT.clear()
            bn.identify = constrained_search if on else idm.identify
            _, coefs = idm.identify(ModelSpec(body_fraction=float(f)), t, t.stances)
            gap = bn.in_sample_gap(t, scales, ModelSpec(body_fraction=float(f)))
            row.append((coefs[:, 0], gap))
        bn.identify = idm.identify
        print(f"  {f:+.2f} | {np.round(row[0][0], 1)} | {row[0][1]:.4f} | {row[1][0][2]:.3g}, {row[1][1]:.4f}",
              flush=True)
    for on, label in ((False, "off"), (True, "on, search constrained (session 16)"), (True, "on (session 17)")):
        idm.EQ7_FIT = on
        if label.endswith("(session 16)"):
            bn.identify = constrained_search
        _, choice = bn.choose_body(rec, trial0)
        bn.identify = idm.identify
        print(f"choose_body EQ7_FIT {label}: {choice.as_json()}", flush=True)


if __name__ == "__main__":
    main()
