"""Launch the hop_impedance pipeline with a full ROS 2 install (launch, launch_ros).

After ``colcon build`` of this repository (packages ``hop_impedance_msgs`` and
``hop_impedance``) and ``source install/setup.bash``:

    ros2 launch hop_impedance pipeline.launch.py recording:=/path/REC.mcap   # replay a recording
    ros2 launch hop_impedance pipeline.launch.py replay:=false               # live: drivers publish the inputs
    ros2 launch hop_impedance pipeline.launch.py replay:=false plates:=true mocap4r2:=true
        # live with one plate per foot (config/plates.yaml) and a MOCAP4ROS2 driver (config/mocap4r2_markers.yaml)

Parameters come from ``config/pipeline.yaml`` (installed to the package's share
folder). Keep ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST unless the inputs come
from another machine. The PyPI wheels used by ``make demo`` carry no launch
system; there ``hop-impedance pipeline`` starts the same nodes.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, SetEnvironmentVariable
from launch.conditions import IfCondition
from launch.substitutions import EnvironmentVariable, LaunchConfiguration
from launch_ros.actions import Node

PACKAGE = "hop_impedance"


def generate_launch_description():
    config = os.path.join(get_package_share_directory(PACKAGE), "config")
    params = os.path.join(config, "pipeline.yaml")

    def node(executable, condition=None, params_file=params, **overrides):
        return Node(
            package=PACKAGE,
            executable=executable,
            name=executable,
            parameters=[params_file, overrides] if overrides else [params_file],
            output="screen",
            condition=condition,
        )

    return LaunchDescription([
        SetEnvironmentVariable(
            "ROS_AUTOMATIC_DISCOVERY_RANGE",
            EnvironmentVariable("ROS_AUTOMATIC_DISCOVERY_RANGE", default_value="LOCALHOST"),
        ),
        DeclareLaunchArgument("recording", default_value="", description="MCAP recording to replay"),
        DeclareLaunchArgument("rate", default_value="1.0", description="replay speed factor (0 = as fast as the nodes take it)"),
        DeclareLaunchArgument("replay", default_value="true", description="start the replay node (false when live)"),
        DeclareLaunchArgument("output", default_value="session_out/pipeline.mcap", description="MCAP written by the recorder"),
        DeclareLaunchArgument("rerun", default_value="false", description="also start the Rerun bridge"),
        DeclareLaunchArgument("plates", default_value="false", description="combine one topic per plate (config/plates.yaml)"),
        DeclareLaunchArgument("mocap4r2", default_value="false", description="markers from a MOCAP4ROS2 driver (config/mocap4r2_markers.yaml)"),
        node("plate_combiner", condition=IfCondition(LaunchConfiguration("plates")),
             params_file=os.path.join(config, "plates.yaml")),
        node("mocap4r2_adapter", condition=IfCondition(LaunchConfiguration("mocap4r2")),
             params_file=os.path.join(config, "mocap4r2_markers.yaml")),
        node("stance_detector"),
        node("inverse_dynamics"),
        node("impedance_estimator"),
        node("recorder", output=LaunchConfiguration("output")),
        node("rerun_bridge", condition=IfCondition(LaunchConfiguration("rerun"))),
        node(
            "replay",
            condition=IfCondition(LaunchConfiguration("replay")),
            recording=LaunchConfiguration("recording"),
            rate=LaunchConfiguration("rate"),
        ),
    ])
