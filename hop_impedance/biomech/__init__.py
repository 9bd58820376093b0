"""Biomechanics core: body model, kinematics, force plate, stance detection, inverse dynamics.

Pure numpy/scipy; no ROS imports.
"""
