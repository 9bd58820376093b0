"""Launch the hop_impedance pipeline with a full ROS 2 install (launch, launch_ros).

    ros2 launch launch/pipeline.launch.py recording:=REC.mcap        # replay a recording
    ros2 launch launch/pipeline.launch.py replay:=false               # live: drivers publish the inputs

Nodes run as ``python3 -m hop_impedance.nodes.<name>`` (the package is a plain
Python package, not an ament package); parameters come from config/pipeline.yaml.
Keep ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST unless the inputs come from another machine.
"""

from pathlib import Path

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, SetEnvironmentVariable
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration

ROOT = Path(__file__).resolve().parent.parent
PARAMS = str(ROOT / "config" / "pipeline.yaml")


def _node(name, *extra, condition=None):
    cmd = ["python3", "-m", f"hop_impedance.nodes.{name}", "--ros-args", "--params-file", PARAMS, *extra]
    return ExecuteProcess(cmd=cmd, name=name, output="screen", condition=condition)


def generate_launch_description():
    return LaunchDescription([
        SetEnvironmentVariable("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST"),
        DeclareLaunchArgument("recording", default_value="recordings/sim_2p20hz_hard.mcap"),
        DeclareLaunchArgument("rate", default_value="1.0"),
        DeclareLaunchArgument("replay", default_value="true"),
        DeclareLaunchArgument("output", default_value="session_out/pipeline.mcap"),
        _node("stance_detector"),
        _node("inverse_dynamics"),
        _node("impedance_estimator"),
        _node("recorder", "-p", ["output:=", LaunchConfiguration("output")]),
        _node("replay", "-p", ["recording:=", LaunchConfiguration("recording")], "-p", ["rate:=", LaunchConfiguration("rate")],
              condition=IfCondition(LaunchConfiguration("replay"))),
    ])
