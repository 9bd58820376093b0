"""hop_impedance: joint impedance of the human ankle, knee and hip in hopping.

Layout (pure numerical core first, ROS adapters last):

- ``hop_impedance.recording``     in-memory recording: force plate, markers, subject
- ``hop_impedance.io``            rosbag2-style MCAP reading and writing
- ``hop_impedance.biomech``       body model, kinematics, stance detection, inverse dynamics
- ``hop_impedance.impedance``     the seed paper's stiffness/damping fit (OSQP) and statistics
- ``hop_impedance.simulation``    forward-dynamics hopping simulator and sensor models
- ``hop_impedance.discovery``     find the effect a model is missing
- ``hop_impedance.importers``     C3D and OpenSim TRC/MOT to contract recordings
- ``hop_impedance.nodes``         thin ROS 2 nodes around the core (the only rclpy users)
- ``hop_impedance.viz``           Rerun logging
- ``hop_impedance.cli``           the ``hop-impedance`` command

Only ``hop_impedance.nodes`` (and the CLI commands that start nodes) import rclpy.
"""


def _version() -> str:
    """The version, written once: ``<version>`` of package.xml (ROS requires it there).

    Run from the repository (editable install, source tree), read that file; installed elsewhere
    (wheel, colcon install space), read the metadata setup.py made from the same file.
    """
    from pathlib import Path

    package_xml = Path(__file__).resolve().parents[1] / "package.xml"
    if package_xml.is_file():
        import xml.etree.ElementTree as ET

        root = ET.parse(package_xml).getroot()
        if root.findtext("name") == "hop_impedance" and root.findtext("version"):
            return root.findtext("version", "").strip()
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as installed_version

    try:
        return installed_version("hop_impedance")
    except PackageNotFoundError:
        return "unknown"


__version__ = _version()
