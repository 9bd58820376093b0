"""What ``make demo`` prints on a recording of a candidate simulator variant (issue 17: "make demo reproduces
the seed's findings" once ``recordings/`` are regenerated from the new hopper).

Simulates one 10-hop trial of ``scenarios.seed_like_options()`` with the variant flags of
``bench/simulator_issue17.py`` (``--bell``, ``--law-scale``, ``--surface``, ``--pad``, ``--trunk``,
``--push-timing``, ...: the same names and meanings, passed through to its ``variant_options``), with the
default realistic sensors (noise, 1 kHz force, 100 Hz markers) as ``recordings/regenerate.sh`` would, writes
it to a temporary MCAP and runs ``hop-impedance demo`` on it; prints the demo's per-stance table and its
comparison with the seed (Table 2, as ``make demo`` prints it) and, since the truth file sits beside the
recording, the demo's own judgement of the hip against the truth's whole hip law (issue 17: the trunk balance adds
to the hip moment, so hip recovery is judged against the whole hip law; ``demo_cmd.truth_lines`` and
:func:`hop_impedance.simulation.whole_hip.judge_hip`: the Eq. 3 fit of the noise-free whole hip moment on the true
hip angle, stance by stance matched by touchdown and as medians). The bundled recordings and the defaults are not
touched.

Usage: nice -n 19 .venv/bin/python bench/demo_on_variant.py [--freq 2.2] [--seed 13] [variant flags]
e.g.   ... --bell 0.9 --law-scale bell09_rigid_pad15_3 --surface rigid --pad 15,3
       ... --hopper seed-like --surface rigid   (the package's preset: since session 14 the bundled Table 1
           recordings' hopper, so with --seed 13 this prints what make demo prints)
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import simulator_issue17 as s17  # noqa: E402

from hop_impedance.io.recording_io import save_recording  # noqa: E402
from hop_impedance.simulation.simulate import simulate_recording  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--freq", type=float, default=2.2)
    ap.add_argument("--seed", type=int, default=13, help="13: the seed of recordings/sim_2p20hz_hard.mcap")
    s17.add_variant_arguments(ap)
    args = s17.VariantArgs(**vars(ap.parse_args()))
    options, said = s17.variant_options(args)
    with tempfile.TemporaryDirectory() as tmp:
        rec_path = os.path.join(tmp, "variant.mcap")
        rec, truth = simulate_recording(args.freq, args.surface, 10, seed=args.seed, **options)
        save_recording(rec_path, rec)
        with open(os.path.join(tmp, "variant.truth.json"), "w") as f:
            json.dump(truth, f, default=str)
        print(f"variant: {said}; {args.freq:g} Hz, {args.surface} surface, seed {args.seed}, realistic sensors", flush=True)
        out = subprocess.run([sys.executable, "-m", "hop_impedance.cli", "demo", rec_path, "--out",
                              os.path.join(tmp, "demo_out")], capture_output=True, text=True, cwd=tmp,
                             env={**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})
    keep = [ln for ln in out.stdout.splitlines() if not ln.startswith("[INFO]") and "Rerun" not in ln
            and not ln.startswith("output:")]
    print("\n".join(keep))
    if out.returncode != 0:
        print(out.stderr[-2000:])
        sys.exit(out.returncode)


if __name__ == "__main__":
    main()
