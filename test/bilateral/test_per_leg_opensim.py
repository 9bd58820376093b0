"""Per-leg inverse dynamics on the real bilateral OpenCap drop jump against OpenSim (issue 21, "must be shown").

Each leg of ``Subject4_DJ1`` (two plates, one per foot; both legs' markers) is
analysed by :func:`hop_impedance.biomech.per_leg.analyze_legs` with its
defaults (rigid-segment fit of the leg's markers, 12 Hz). OpenSim then gets an
equivalent planar model of that leg (the per-leg body model in the same
four-body OpenSim model as the lumped check, ``test/biomech/opensim_model.py``)
and that foot's plate wrench (zeroed and low-passed as the analysis does):

- its InverseKinematicsTool fits the model, with the leg's markers attached,
  to the same markers: the coordinates must be ours (the fit is the same
  problem, solved by a different solver);
- its InverseDynamicsTool, driven by our fitted coordinates and driven by its
  own IK's coordinates (both low-passed at 12 Hz by the project's filter, as
  the analysis does), must give each leg's ankle, knee and hip moments within
  2 % of each joint's peak at every stance sample.

The last test keeps the measured limit that made the rigid fit necessary: on
the skin markers as measured (``rigid=False``) the two disagree by 17-33 %.
"""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from hop_impedance.biomech.analysis import recording_span
from hop_impedance.biomech.filtering import fill_gaps, sampling_rate_hz
from hop_impedance.biomech.force_plate import flight_intervals, flight_offsets, subtract_offsets
from hop_impedance.biomech.inverse_dynamics import EXTENSOR_SIGN
from hop_impedance.biomech.kinematics import _POINT_IDX, compute_kinematics, sagittal_markers, wrench_through_marker_chain

OPENCAP = Path("/work/shared/data_candidates/opencap_dropjump")
TRC, MOT = OPENCAP / "Subject4_DJ1_markers_trc.txt", OPENCAP / "Subject4_DJ1_grf_mot.txt"
if importlib.util.find_spec("opensim") is None:  # not imported here: see opensim_model._opensim
    pytest.skip("OpenSim (PyPI 'opensim') is a test dependency", allow_module_level=True)
if not TRC.exists():
    pytest.skip("shared data set opencap_dropjump not present", allow_module_level=True)
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "biomech"))  # the one OpenSim model of the lumped check
from opensim_model import _opensim, build_model, run_inverse_dynamics  # noqa: E402

from hop_impedance.bilateral import SIDES  # noqa: E402
from hop_impedance.biomech.per_leg import analyze_legs, fit_leg_pose, rigid_leg_markers, smooth_pose  # noqa: E402
from hop_impedance.importers.bilateral_import import import_opensim_bilateral  # noqa: E402
from hop_impedance.recording import MARKER_NAMES  # noqa: E402


@pytest.fixture(scope="module")
def raw():
    return import_opensim_bilateral(TRC, MOT, mass_kg=60.0)


@pytest.fixture(scope="module")
def legs(raw):
    return analyze_legs(raw)


def _write_trc(path: Path, t: np.ndarray, xz: np.ndarray) -> None:
    """The six markers as an OpenSim TRC file (OpenSim x, y = our x, z; the plane z = 0)."""
    rate = sampling_rate_hz(t)
    with open(path, "w") as fh:
        fh.write(f"PathFileType\t4\t(X/Y/Z)\t{path.name}\n")
        fh.write("DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n")
        fh.write(f"{rate:g}\t{rate:g}\t{len(t)}\t{len(MARKER_NAMES)}\tm\t{rate:g}\t1\t{len(t)}\n")
        fh.write("Frame#\tTime\t" + "\t\t\t".join(MARKER_NAMES) + "\n")
        fh.write("\t\t" + "\t".join(f"X{i + 1}\tY{i + 1}\tZ{i + 1}" for i in range(len(MARKER_NAMES))) + "\n\n")
        for k, tk in enumerate(t):
            fh.write(f"{k + 1}\t{tk:.9g}\t" + "\t".join(f"{x:.9g}\t{z:.9g}\t0" for x, z in xz[k]) + "\n")


def opensim_ik(model, t: np.ndarray, xz: np.ndarray, workdir: Path) -> np.ndarray:
    """OpenSim's InverseKinematicsTool on the planar leg model with the six markers attached; the pose (N, 6)
    in :data:`POSE_COORDINATES` order. Weights: 1 for the leg's five markers, 1e-3 for the head (the HAT is not
    part of the leg: the head must not pull the leg's pose, as in ``fit_leg_pose``; it only sets q4)."""
    osim = _opensim()
    m = build_model(model)
    g = model.foot_geometry
    places = {"toe": ("foot", 0.0, 0.0), "heel": ("foot", g.heel_along_m, g.heel_perp_m), "ankle": ("foot", g.toe_ankle_m, 0.0),
              "knee": ("shank", model.shank.length_m, 0.0), "hip": ("thigh", model.thigh.length_m, 0.0),
              "head": ("hat", model.hat.length_m, 0.0)}  # body frames: origin at the distal joint, x towards the proximal
    for name, (body, along, perp) in places.items():
        m.addMarker(osim.Marker(name, m.getBodySet().get(body), osim.Vec3(along, perp, 0)))
    m.finalizeConnections()
    m.initSystem()
    _write_trc(workdir / "markers.trc", t, xz)
    tool = osim.InverseKinematicsTool()
    tool.setModel(m)
    tool.setMarkerDataFileName(str(workdir / "markers.trc"))
    for name in MARKER_NAMES:
        task = osim.IKMarkerTask()
        task.setName(name)
        task.setApply(True)
        task.setWeight(1e-3 if name == "head" else 1.0)
        tool.getIKTaskSet().cloneAndAppend(task)
    tool.setStartTime(float(t[0]))
    tool.setEndTime(float(t[-1]))
    tool.set_accuracy(1e-9)
    tool.setResultsDir(str(workdir))
    tool.setOutputMotionFileName(str(workdir / "ik.mot"))
    if not tool.run():
        raise RuntimeError("OpenSim InverseKinematicsTool failed")
    table = osim.TimeSeriesTable(str(workdir / "ik.mot"))
    assert len(table.getIndependentColumn()) == len(t)

    def col(name):
        return table.getDependentColumn(name).to_numpy()

    deg = np.pi / 180  # rotational coordinates are written in degrees
    q4 = col("root_rz") * deg
    q3 = q4 + col("hip_q") * deg
    q2 = q3 + col("knee_q") * deg
    q1 = q2 + col("ankle_q") * deg
    return np.column_stack([col("root_tx"), col("root_ty"), q1, q2, q3, q4])


def _analysis_inputs(rec, analysis, filter_t_s=None):
    """The zeroed wrench through the markers' chain as the analysis uses it (same functions, same options: measured
    at the plates' stamps, low-passed on ``filter_t_s``, the rigid fit's 1 kHz grid, or on the markers' own stamps)
    and the leg's markers, gaps filled."""
    data = recording_span(rec)
    t, opts = data.force_t_s, analysis.options
    flights = flight_intervals([(s.touchdown_s, s.takeoff_s) for s in analysis.stances], float(t[0]), float(t[-1]))
    centres, offsets = flight_offsets(t, data.wrench, flights, opts.flight_margin_s)
    assert np.array_equal(data.marker_t_s, t)  # OpenCap: markers and plates both at 100 Hz on the same stamps
    zeroed = subtract_offsets(t, data.wrench, centres, offsets)
    wrench = wrench_through_marker_chain(t, zeroed, t, t if filter_t_s is None else filter_t_s, opts.force_cutoff_hz)
    xz, _, _ = fill_gaps(t, data.markers_xz, opts.max_gap_s)
    return t, wrench, xz


def _contact(analysis):
    accepted = [s for s in analysis.stances if s.joints is not None]
    assert len(accepted) == 1  # the landing + rebound contact; the second landing is cut by the file's end
    return accepted[0]


def _opensim_against_ours(analysis, t, wrench, pose, tmp_path, label, side) -> np.ndarray:
    """max |ours - OpenSim ID driven by ``pose``| / peak per joint over the leg's accepted contact."""
    stance = _contact(analysis)
    sel = (t >= stance.touchdown_s) & (t <= stance.takeoff_s)
    assert np.count_nonzero(sel) == len(stance.joints.time_s)
    # OpenSim gets 0.1 s more on each side so that the ends of its spline of the coordinates fall in flight
    wide = (t >= stance.touchdown_s - 0.1) & (t <= stance.takeoff_s + 0.1)
    out = run_inverse_dynamics(analysis.model, t[wide], pose[wide, 2:6], pose[wide, :2], wrench[wide], tmp_path)
    theirs = np.column_stack([out[n] for n in ("ankle", "knee", "hip")])[sel[wide]] * EXTENSOR_SIGN
    mine = stance.joints.moment_nm
    peak = np.max(np.abs(mine), axis=0)
    assert np.all(peak > 50)  # N m: a real one-leg landing, not an empty plate
    rel = np.max(np.abs(mine - theirs), axis=0) / peak
    print(f"{side}, OpenSim ID on {label}: peak {np.round(peak, 1)} N m, max |ours - OpenSim| / peak {np.round(100 * rel, 2)} %")
    return rel


def test_marker_segment_lengths_vary(raw):
    """Why the per-leg kinematics fit a rigid leg: the raw markers' segment lengths over the contact."""
    t = (raw.recording.markers.stamp_ns - raw.recording.start_ns) * 1e-9
    contact = (t >= 1.42) & (t <= 2.16)  # SOURCE.txt: first contact 1.42-2.17 s
    spread = []
    for side in SIDES:
        p = raw.markers(side).positions_m[contact][..., [0, 2]][:, _POINT_IDX]
        lengths = np.linalg.norm(np.diff(p[:, :4], axis=1), axis=2)  # toe-ankle, ankle-knee, knee-hip
        spread.append(np.max(np.abs(lengths - np.median(lengths, axis=0)), axis=0))
    spread = np.max(spread, axis=0)
    print(f"max |segment length - median| over the contact (toe-ankle, ankle-knee, knee-hip): {np.round(100 * spread, 2)} cm")
    assert np.all(spread > 0.005)  # several millimetres to centimetres: skin markers, not a rigid leg


@pytest.mark.parametrize("side", SIDES)
def test_rigid_fit_is_opensim_inverse_kinematics(raw, legs, side, tmp_path):
    """Our Gauss-Newton fit and OpenSim's IK solve the same least-squares problem on the same markers.
    Measured: hip position within 0.04 mm, segment angles within 0.007 deg, every frame of the trial."""
    t = (raw.markers(side).stamp_ns - raw.recording.start_ns) * 1e-9
    xz, _, _ = fill_gaps(t, sagittal_markers(raw.markers(side)), legs[side].options.max_gap_s)
    ours = fit_leg_pose(xz, legs[side].model)
    theirs = opensim_ik(legs[side].model, t, xz, tmp_path)
    hip_mm = 1000 * np.max(np.abs(ours[:, :2] - theirs[:, :2]))
    angle_deg = np.degrees(np.max(np.abs(ours[:, 2:5] - theirs[:, 2:5])))
    print(f"{side}: our fit vs OpenSim IK over {len(t)} frames: hip {hip_mm:.3f} mm, leg angles {angle_deg:.4f} deg")
    assert hip_mm < 0.2 and angle_deg < 0.05
    # and the fit is a fit, not the markers: the skin moves the markers by millimetres to centimetres off the rigid leg
    _, _, fit_rms = rigid_leg_markers(raw.markers(side), legs[side].model, legs[side].options.marker_cutoff_hz, 0.1)
    print(f"{side}: RMS marker distance to the fitted leg, median {1000 * np.median(fit_rms):.1f} mm, "
          f"max {1000 * np.max(fit_rms):.1f} mm")
    assert 0.003 < np.median(fit_rms) < 0.02


@pytest.mark.parametrize("side", SIDES)
def test_leg_moments_agree_with_opensim_within_2_percent(raw, legs, side, tmp_path):
    """Default per-leg analysis (rigid fit, 12 Hz) against OpenSim's InverseDynamicsTool driven by the same
    coordinates, and by OpenSim's own IK of the markers (same 1 kHz 12 Hz filter). Measured (ankle / knee / hip,
    % of each joint's peak): our coordinates left 0.00 / 0.01 / 0.02, right 0.00 / 0.02 / 0.04; OpenSim IK's
    left 0.00 / 0.01 / 0.03, right 0.00 / 0.02 / 0.04. The issue asks 2 %; held to 0.5 % so a regression shows."""
    analysis = legs[side]
    # per-leg body: half the lumped leg segments (de Leva one side: 1.29 % foot, 4.81 % shank, 14.78 % thigh of 60 kg)
    np.testing.assert_allclose([analysis.model.foot.mass_kg, analysis.model.shank.mass_kg, analysis.model.thigh.mass_kg],
                               [0.0129 * 60, 0.0481 * 60, 0.1478 * 60], rtol=1e-12)
    assert any(w.startswith(f"{side} leg: kinematics of a rigid-segment fit") for w in analysis.warnings)
    cutoff = analysis.options.marker_cutoff_hz
    assert cutoff == 12.0  # the default, as the analysis ran
    markers, pose, _ = rigid_leg_markers(raw.markers(side), analysis.model, cutoff, analysis.options.max_gap_s)
    grid = (markers.stamp_ns - raw.recording.start_ns) * 1e-9
    t, wrench, xz = _analysis_inputs(raw.leg(side), analysis, grid)

    def on_force_time(p):  # the coordinates at the plate's samples (on the 1 kHz grid: no interpolation error)
        return np.column_stack([np.interp(t, grid, c) for c in p.T])

    (tmp_path / "ours").mkdir()
    rel = _opensim_against_ours(analysis, t, wrench, on_force_time(pose), tmp_path / "ours", "our fit's coordinates", side)
    assert np.all(rel < 0.005), rel
    (tmp_path / "ik").mkdir()
    ik_grid, ik = smooth_pose(t, opensim_ik(analysis.model, t, xz, tmp_path / "ik"), cutoff)  # the same 1 kHz 12 Hz filter
    np.testing.assert_allclose(ik_grid, grid, atol=1e-9)
    rel_ik = _opensim_against_ours(analysis, t, wrench, on_force_time(ik), tmp_path / "ik", "OpenSim IK's coordinates", side)
    assert np.all(rel_ik < 0.005), rel_ik


def test_raw_skin_markers_are_not_a_rigid_problem(raw, tmp_path):
    """The limit the rigid fit removes, measured with ``rigid=False`` (the v1 kinematics on each leg's markers as
    measured, 12 Hz), against OpenSim ID on those kinematics' own angles and hip path: tens of percent of peak
    (skin markers change segment lengths by up to 2.9 cm and per-marker filtering bends a rigid leg in the impact;
    our frame-by-frame joint points and a rigid multibody model solve different problems there)."""
    analyses = analyze_legs(raw, rigid=False)
    for side in SIDES:
        analysis = analyses[side]
        t, wrench, _ = _analysis_inputs(raw.leg(side), analysis)
        data = recording_span(raw.leg(side))
        kin, _ = compute_kinematics(data.marker_t_s, data.markers_xz, t, analysis.model, analysis.options.marker_cutoff_hz)
        pose = np.column_stack([kin.points_xz[:, 3], kin.q])
        (tmp_path / side).mkdir()
        rel = _opensim_against_ours(analysis, t, wrench, pose, tmp_path / side, "the skin markers' angles", side)
        assert np.max(rel) > 0.05
