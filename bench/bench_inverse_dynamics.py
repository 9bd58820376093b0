"""Speed of the kinematics + inverse dynamics stage, ours vs OpenSim's InverseDynamicsTool.

A 60 s trial (1 kHz force, 100 Hz markers) of the four-segment model with the
toe pinned and smooth joint motion (test/biomech/biomech_synth.py). Ours:
marker gap filling, 12 Hz zero-lag filtering, splines onto force time,
angles/COMs and their derivatives, plate-wrench filtering and bottom-up
Newton-Euler for every force frame (``compute_kinematics`` + ``lowpass`` +
``inverse_dynamics_2d``). OpenSim: InverseDynamicsTool on the same joint
angles, hip path and ground wrench (file writing included, model building
excluded). Both single-threaded (OpenSim's ID is serial; numpy here is
limited to one thread below).

Goal: >= 100x faster than OpenSim and > 2,000x real time on one core.

Run: .venv/bin/python bench/bench_inverse_dynamics.py [--seconds 60] [--no-opensim]
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "test" / "biomech"))
from biomech_synth import make_model, markers_from_points, pinned_chain  # noqa: E402

from hop_impedance.biomech.filtering import lowpass  # noqa: E402
from hop_impedance.biomech.inverse_dynamics import inverse_dynamics_2d  # noqa: E402
from hop_impedance.biomech.kinematics import compute_kinematics  # noqa: E402


def ours(tm, markers, tf, wrench, model):
    kin, _ = compute_kinematics(tm, markers, tf, model)
    smooth = lowpass(wrench, 1000.0, 12.0)
    return kin, inverse_dynamics_2d(kin.points_xz, kin.com_xz, kin.com_acc, kin.qdd, smooth, model)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-opensim", action="store_true")
    args = ap.parse_args()
    model = make_model()
    tm = np.arange(0, args.seconds, 0.01)
    tf = np.arange(0, args.seconds, 0.001)
    markers = markers_from_points(pinned_chain(tm, model)["points"], model)[..., [0, 2]]
    wrench = pinned_chain(tf, model)["wrench"]
    best = np.inf
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        kin, loads = ours(tm, markers, tf, wrench, model)
        best = min(best, time.perf_counter() - t0)
    n = tf.size
    print(f"trial: {args.seconds:g} s, {n} force frames (1 kHz), {tm.size} marker frames (100 Hz)")
    print(f"ours   : {best * 1e3:9.1f} ms  {n / best:12.0f} frames/s  {args.seconds / best:9.0f}x real time")
    if args.no_opensim:
        return 0
    try:
        from opensim_model import run_inverse_dynamics
    except ImportError as exc:  # pragma: no cover
        print(f"opensim: not available ({exc})")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        out = run_inverse_dynamics(model, tf, kin.q, kin.points_xz[:, 3], wrench, Path(tmp))
        t_os = time.perf_counter() - t0
    print(f"opensim: {t_os * 1e3:9.1f} ms  {n / t_os:12.0f} frames/s  {args.seconds / t_os:9.0f}x real time")
    print(f"ratio  : ours is {t_os / best:.0f}x faster than OpenSim InverseDynamicsTool")
    inner = slice(1000, n - 1000)
    diff = np.max(np.abs(out["ankle"][inner] + loads.moment_nm[inner, 0]))
    print(f"check  : max |ankle difference| away from the ends {diff:.3f} N m "
          f"(peak {np.nanmax(np.abs(loads.moment_nm[:, 0])):.0f} N m; OpenSim gets unfiltered GRF here)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
