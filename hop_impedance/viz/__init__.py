"""Rerun views of hopping: stick figure with GRF, time series, per-stance fits, trends.

Pure numpy + rerun-sdk (no ROS). Every logging function takes an explicit
``rerun.RecordingStream``; the offline ``hop-impedance view`` command
(:mod:`hop_impedance.viz.session`) and the live ``rerun_bridge`` node call
the same functions (:mod:`hop_impedance.viz.views`). Layout:
:func:`hop_impedance.viz.blueprint.default_blueprint`. Entity paths:
:mod:`hop_impedance.viz.style`. See docs/rerun.md.
"""
