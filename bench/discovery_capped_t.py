"""What a cap on the per-stance log gap ratios would change in the held-out screen (a lead, not the method).

The screen's one-sided t-test (``forward_selection.one_sided_t``) over the held-out stances' log gap ratios
``d_i = log G_cur,i - log G_cand,i`` loses power where one stance's current model fails outright: its ``d_i``
(5-8) inflates the SD more than the mean. Session 15's sweep of our simulator (``discovery_hit_rates.py --cases
<the ten> --seeds 1 --hops 8 --json-dir DIR``) had all 8 ratios positive on the angle + offset recording and p
0.033 > 0.05/8, because the baseline's simulation of one stance failed (its gap 9.1 against 0.04 elsewhere).

This bench reads discover documents (``--json-dir`` output, or ``hop-impedance discover --json``) and prints,
for each round-0 candidate that passes the screen with either test (admissible, pooled shrink >= 10 %), the p
of the test as it is and with every ``d_i`` capped at +-``--cap`` (default log 10: a stance counts at most as an
order of magnitude). Only the screen is recomputed: the stiffness gate and later rounds are not re-run, so a
NEW or LOST is where the method would have to be re-measured (nulls of both generators, outside files).

Usage: .venv/bin/python bench/discovery_capped_t.py DOC.json [DOC.json ...] [--cap 2.3026]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from hop_impedance.discovery.forward_selection import ALPHA, MIN_SHRINK, one_sided_t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("docs", nargs="+")
    ap.add_argument("--cap", type=float, default=float(np.log(10.0)))
    args = ap.parse_args()
    for path in args.docs:
        round0 = json.loads(Path(path).read_text())["selection"]["rounds"][0]
        level = ALPHA / len(round0)
        cells = []
        for effect, c in round0.items():
            if not (c["physics"]["admissible"] and c["held_out_shrink"] >= MIN_SHRINK):
                continue
            d = np.nan_to_num(np.asarray(c["per_stance_log_gap_ratio"], float), nan=0.0, posinf=10.0, neginf=-10.0)
            p_now, p_cap = c["p_value"], one_sided_t(np.clip(d, -args.cap, args.cap))
            if min(p_now, p_cap) < level:
                change = " NEW" if p_cap < level <= p_now else (" LOST" if p_now < level <= p_cap else "")
                cells.append(f"{effect}: p {p_now:.2g} -> {p_cap:.2g}{change}")
        print(f"{Path(path).name[:48]:48s} (alpha {level:.4f}) " + ("; ".join(cells) or "-"))


if __name__ == "__main__":
    main()
