"""Time per stance of the full impedance fit (reduction + OSQP) for three joints.

Goal (issue 5): under 5 ms per stance on one core. Prints median and p99 over
synthetic noisy stances at the seed's three frequencies (200 Hz samples), one
reusable OSQP workspace per joint as in the live stage.

    .venv/bin/python bench/bench_impedance_fit.py [--stances 300]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares
from hop_impedance.impedance.stance_fit import FitOptions, fit_joint_stance
from hop_impedance.impedance.synthetic import synthetic_stance

JOINTS = ("ankle", "knee", "hip")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stances", type=int, default=300, help="stances per frequency")
    parser.add_argument("--rate-hz", type=float, default=200.0, help="sample rate of the stance arrays (Hz)")
    args = parser.parse_args()
    options = FitOptions(noise_bandwidth_hz=12.0)
    solvers = {joint: ConstrainedLeastSquares() for joint in JOINTS}
    rng = np.random.default_rng(0)
    for freq in (1.53, 1.87, 2.20):
        stances = [
            {j: synthetic_stance(j, freq, rng, rate_hz=args.rate_hz, realistic_noise=True) for j in JOINTS}
            for _ in range(args.stances)
        ]
        times, rejected = [], 0
        for stance in stances:
            t0 = time.perf_counter()
            for joint, st in stance.items():
                fit = fit_joint_stance(
                    st.time_s, st.angle_rad, st.angular_velocity_rad_s, st.moment_nm, options, solver=solvers[joint]
                )
                rejected += not fit.ok
            times.append(time.perf_counter() - t0)
        ms = np.array(times) * 1e3
        n = stances[0]["ankle"].time_s.size
        print(
            f"{freq:.2f} Hz, {n} samples/stance, 3 joints: median {np.median(ms):.2f} ms, "
            f"p99 {np.percentile(ms, 99):.2f} ms per stance (goal < 5 ms); rejected {rejected}"
        )


if __name__ == "__main__":
    main()
