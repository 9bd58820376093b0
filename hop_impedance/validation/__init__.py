"""End-to-end checks of the pipeline against the simulator's known truth (no ROS imports)."""
