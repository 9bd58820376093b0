"""Draw docs/importing_dropjump.png: the OpenCap drop jump imported and analysed.

Run: .venv/bin/python test/importers/make_dropjump_figure.py  (prints the figures it plots)
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hop_impedance.biomech.analysis import analyze_recording  # noqa: E402
from hop_impedance.importers import import_opensim  # noqa: E402
from hop_impedance.importers.opensim_import import read_mot  # noqa: E402

D = Path("/work/shared/data_candidates/opencap_dropjump")
OUT = Path(__file__).resolve().parents[2] / "docs" / "importing_dropjump.png"


def main() -> int:
    rec = import_opensim(D / "Subject4_DJ1_markers_trc.txt", D / "Subject4_DJ1_grf_mot.txt", mass_kg=60.0)
    res = analyze_recording(rec)
    st = next(s for s in res.stances if s.rejection_reason is None)
    j = st.joints
    t_abs = j.time_s + st.touchdown_s
    ik = read_mot(D / "Subject4_DJ1_ik_mot.txt")
    from hop_impedance.impedance.recording_fits import fit_stance_joints

    # The fits `hop-impedance analyze` publishes (fit options from the analysis' cut-off).
    fits = list(fit_stance_joints(st).values())
    fig, ax = plt.subplots(2, 2, figsize=(11, 7), constrained_layout=True)
    t = rec.force.stamp_ns / 1e9
    ax[0, 0].plot(t, rec.force.force_n[:, 2] / (60 * 9.81), "k", label="Fz (both plates)")
    ax[0, 0].plot(t, rec.force.force_n[:, 0] / (60 * 9.81), "C1", label="Fx")
    for s in res.stances:
        ax[0, 0].axvspan(s.touchdown_s, s.takeoff_s, color="C0" if s.rejection_reason is None else "0.8", alpha=0.2)
    ax[0, 0].set(xlabel="time (s)", ylabel="GRF (body weights)", title="Imported GRF, detected contacts (blue = fitted)")
    ax[0, 0].legend()
    names = ("ankle", "knee", "hip")
    ax[0, 1].plot(t_abs, np.degrees(j.angle_rad[:, 1] - np.pi), "C0", label="knee rho2 - 180 (ours)")
    ax[0, 1].plot(ik.column("time"), np.degrees(ik.column("knee_angle_r")), "C0--", label="knee, OpenSim IK")
    ax[0, 1].plot(t_abs, np.degrees(j.angle_rad[:, 2] - np.pi), "C2", label="hip rho3 - 180 (ours, incl. trunk)")
    ax[0, 1].plot(ik.column("time"), np.degrees(ik.column("hip_flexion_r")), "C2--", label="hip flexion, OpenSim IK")
    ax[0, 1].set(xlim=(st.touchdown_s - 0.1, st.takeoff_s + 0.1), xlabel="time (s)", ylabel="flexion (deg)",
                 title="Angles vs OpenSim IK")
    ax[0, 1].legend(fontsize=8)
    for k, n in enumerate(names):
        ax[1, 0].plot(j.time_s, j.moment_nm[:, k] / 60, f"C{k}", label=n)
        if fits[k].rejection_reason is None and fits[k].moment_fit.size:
            ax[1, 0].plot(fits[k].time_s + j.time_s[0], fits[k].moment_fit / 60, f"C{k}:",
                          label=f"{n} fit (R2 {fits[k].r_squared:.2f})")
    ax[1, 0].set(xlabel="time since touchdown (s)", ylabel="net moment, both legs (N m/kg)", title="Inverse dynamics, extensor +")
    ax[1, 0].legend(fontsize=8)
    for k, n in enumerate(names):
        f = fits[k]
        if f.rejection_reason is None and f.stiffness.size and np.any(f.stiffness):
            ax[1, 1].plot(f.time_s + j.time_s[0], f.stiffness, f"C{k}", label=f"{n} stiffness")
        print(f"{n}: peak moment {np.nanmax(j.moment_nm[:, k]) / 60:.2f} N m/kg (both legs), fit status {f.status}, "
              f"R2 {f.r_squared:.2f}, terms {f.terms}, "
              f"mean stiffness {np.nanmean(f.stiffness) if f.stiffness.size else np.nan:.0f} N m/rad")
    ax[1, 1].set(xlabel="time since touchdown (s)", ylabel="stiffness (N m/rad)", title="Impedance fits (seed Eqs. 3-9)")
    ax[1, 1].legend(fontsize=8)
    fig.suptitle("OpenCap Subject4 drop jump DJ1: TRC + MOT imported to the contract, analysed")
    fig.savefig(OUT, dpi=90)
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
