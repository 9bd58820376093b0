"""The four-segment sagittal model rebuilt in OpenSim, and a runner for its InverseDynamicsTool.

Mapping: our lab x (forward), z (up) -> OpenSim x, y (Y up); our -y -> OpenSim z,
so a counter-clockwise angle in our x-z picture is a positive rotation about
OpenSim's z. Every body frame has its origin at the segment's distal joint
and its x axis along distal -> proximal, exactly like our segment frames.

Tree rooted at the HAT (PlanarJoint to ground: rz = q4, tx/ty = hip), then
hip (q3 - q4), knee (q2 - q3), ankle (q1 - q2) pin joints down to the foot,
which receives the ground reaction. OpenSim then computes each pin torque
from the bodies *distal* to it plus the external load: the same bottom-up
problem we solve, by a different method (multibody mass matrix, its own
spline differentiation of the coordinates).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _opensim():
    """Import opensim without its default ``opensim.log`` file in the working directory.

    ``import opensim`` overwrites ``LD_LIBRARY_PATH`` with ``PATH`` (and
    prepends to ``PATH``) for the whole process; restore both so that later
    child processes can still load the ROS 2 wheels' libraries.
    """
    import os

    saved = {k: os.environ.get(k) for k in ("LD_LIBRARY_PATH", "PATH")}
    import opensim as osim

    for key, value in saved.items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value

    osim.Logger.removeFileSink()
    osim.Logger.setLevelString("error")
    return osim


def build_model(model):
    """An ``opensim.Model`` equivalent to our :class:`BodyModel`."""
    osim = _opensim()

    m = osim.Model()
    m.setName("hop4")
    m.setGravity(osim.Vec3(0, -9.81, 0))
    lengths = {"foot": model.foot_geometry.toe_ankle_m, "shank": model.shank.length_m, "thigh": model.thigh.length_m}
    bodies = {}
    for seg in model.segments:
        inertia = osim.Inertia(seg.inertia_kgm2, seg.inertia_kgm2, seg.inertia_kgm2)
        b = osim.Body(seg.name, seg.mass_kg, osim.Vec3(seg.com_along_m, seg.com_perp_m, 0), inertia)
        m.addBody(b)
        bodies[seg.name] = b
    zero = osim.Vec3(0, 0, 0)
    m.addJoint(osim.PlanarJoint("root", m.getGround(), zero, zero, bodies["hat"], zero, zero))
    chain = [("hip", "hat", "thigh"), ("knee", "thigh", "shank"), ("ankle", "shank", "foot")]
    for name, parent, child in chain:
        m.addJoint(osim.PinJoint(name, bodies[parent], zero, zero, bodies[child], osim.Vec3(lengths[child], 0, 0), zero))
    root = m.getJointSet().get("root")
    for i, c in enumerate(("root_rz", "root_tx", "root_ty")):
        root.upd_coordinates(i).setName(c)
    for name, _, _ in chain:
        m.getJointSet().get(name).upd_coordinates(0).setName(f"{name}_q")
    m.finalizeConnections()
    m.initSystem()
    return m


def _write_table(path: Path, name: str, labels: list[str], data: np.ndarray, in_degrees: bool) -> None:
    with open(path, "w") as fh:
        fh.write(f"{name}\nversion=1\nnRows={data.shape[0]}\nnColumns={data.shape[1]}\n")
        fh.write(f"inDegrees={'yes' if in_degrees else 'no'}\nendheader\n")
        fh.write("\t".join(labels) + "\n")
        for row in data:
            fh.write("\t".join(f"{v:.12g}" for v in row) + "\n")


def run_inverse_dynamics(model, t, q, hip_xz, wrench, workdir: Path) -> dict[str, np.ndarray]:
    """OpenSim generalized forces for our kinematics and ground wrench.

    Parameters
    ----------
    t : (N,) s; q : (N, 4) segment angles; hip_xz : (N, 2) m;
    wrench : (N, 3) [Fx, Fz, Mo ccw about the lab origin].

    Returns
    -------
    dict with ``time`` and ``ankle``, ``knee``, ``hip`` torques (N m) as OpenSim
    reports them (positive increasing its coordinate).
    """
    osim = _opensim()
    workdir = Path(workdir)
    osim_model = build_model(model)
    coords = np.column_stack([t, q[:, 3], hip_xz[:, 0], hip_xz[:, 1], q[:, 2] - q[:, 3], q[:, 1] - q[:, 2], q[:, 0] - q[:, 1]])
    _write_table(workdir / "coords.mot", "coords", ["time", "root_rz", "root_tx", "root_ty", "hip_q", "knee_q", "ankle_q"],
                 coords, False)
    n = t.size
    grf = np.column_stack([t, wrench[:, 0], wrench[:, 1], np.zeros(n), np.zeros((n, 3)), np.zeros(n), np.zeros(n), wrench[:, 2]])
    labels = ["time", "ground_force_vx", "ground_force_vy", "ground_force_vz", "ground_force_px", "ground_force_py",
              "ground_force_pz", "ground_torque_x", "ground_torque_y", "ground_torque_z"]
    _write_table(workdir / "grf.mot", "grf", labels, grf, False)
    loads = osim.ExternalLoads()
    ef = osim.ExternalForce()
    ef.setName("grf")
    ef.set_applied_to_body("foot")
    ef.set_force_expressed_in_body("ground")
    ef.set_point_expressed_in_body("ground")
    ef.set_force_identifier("ground_force_v")
    ef.set_point_identifier("ground_force_p")
    ef.set_torque_identifier("ground_torque_")
    ef.set_data_source_name(str(workdir / "grf.mot"))
    loads.cloneAndAppend(ef)
    loads.setDataFileName(str(workdir / "grf.mot"))
    loads.printToXML(str(workdir / "loads.xml"))
    tool = osim.InverseDynamicsTool()
    tool.setModel(osim_model)
    tool.setCoordinatesFileName(str(workdir / "coords.mot"))
    tool.setExternalLoadsFileName(str(workdir / "loads.xml"))
    tool.setLowpassCutoffFrequency(-1)
    tool.setStartTime(float(t[0]))
    tool.setEndTime(float(t[-1]))
    tool.setResultsDir(str(workdir))
    tool.setOutputGenForceFileName("id.sto")
    if not tool.run():
        raise RuntimeError("OpenSim InverseDynamicsTool failed")
    table = osim.TimeSeriesTable(str(workdir / "id.sto"))
    out = {"time": np.array(table.getIndependentColumn())}
    for name in ("ankle", "knee", "hip"):
        out[name] = table.getDependentColumn(f"{name}_q_moment").to_numpy()
    return out
