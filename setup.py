"""Python packaging for hop_impedance (also used by colcon's ament_python build)."""

import xml.etree.ElementTree as ET
from glob import glob
from pathlib import Path

from setuptools import find_packages, setup

PACKAGE = "hop_impedance"

setup(
    name=PACKAGE,
    # written once, in package.xml (ROS requires it there); hop_impedance.__version__ reads it too
    version=ET.parse(Path(__file__).resolve().parent / "package.xml").findtext("version"),
    packages=find_packages(include=[PACKAGE, f"{PACKAGE}.*"]),
    package_data={PACKAGE: ["py.typed", "data/*.yaml", "data/marker_maps/*.yaml"]},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/launch", glob("launch/*.py")),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
    ],
    python_requires=">=3.10",
    install_requires=[
        "numpy>=1.24",
        "scipy>=1.11",
        # the stance ODE's compiled equations of motion (simulation.dynamics)
        "numba>=0.60",
        "osqp>=1.0",
        "mcap>=1.2",
        "mcap-ros2-support>=0.5",
        "pyyaml>=6",
        "matplotlib>=3.7",
        # C3D import (hop-impedance import): a maintained reader/writer, not hand-parsed binary.
        "ezc3d>=1.7",
    ],
    extras_require={"viz": ["rerun-sdk>=0.41"]},
    zip_safe=True,
    maintainer="hop_impedance developers",
    maintainer_email="maintainers@hop-impedance.invalid",
    description="Stance-by-stance joint stiffness and damping of human hopping, as ROS 2 nodes",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "hop-impedance = hop_impedance.cli.main:main",
            # One executable per node, so `ros2 run hop_impedance <node>` and launch_ros work
            # after a colcon build (setup.cfg installs them into lib/hop_impedance).
            "replay = hop_impedance.nodes.replay:main",
            "stance_detector = hop_impedance.nodes.stance_detector:main",
            "inverse_dynamics = hop_impedance.nodes.inverse_dynamics:main",
            "impedance_estimator = hop_impedance.nodes.impedance_estimator:main",
            "recorder = hop_impedance.nodes.recorder:main",
            "rerun_bridge = hop_impedance.nodes.rerun_bridge:main",
            # Live inputs of labs (issue 19): one plate per foot, MOCAP4ROS2 drivers.
            "plate_combiner = hop_impedance.nodes.plate_combiner:main",
            "mocap4r2_adapter = hop_impedance.nodes.mocap4r2_adapter:main",
        ],
    },
)
