"""``StanceKinetics`` round trip (inverse_dynamics' ``stance_message`` / ``stance_from_message``).

What the estimator fits must be what inverse_dynamics analysed: the joint series bit for bit
(float64[] fields set from ``array.array``) and the window's reach past take-off, which decides
the hip fit's take-off exclusion (``recording_fits.takeoff_exclusion_s``); a message whose
field was never set (0, the default) is a whole-record stance.
"""

from __future__ import annotations

import numpy as np
from hop_impedance_msgs.msg import StanceKinetics
from rclpy.serialization import deserialize_message, serialize_message

from hop_impedance.biomech.analysis import AnalysisOptions, analyze_recording
from hop_impedance.nodes.inverse_dynamics import stance_from_message, stance_message
from test.cli import bad_recordings as bad


def test_stance_round_trip_keeps_series_and_window():
    rec = bad.bundled()
    for options, expected in ((AnalysisOptions(post_takeoff_s=0.005), 0.005), (AnalysisOptions(), None)):
        analysis = analyze_recording(rec, options)
        stance = next(s for s in analysis.stances if s.joints is not None)
        wire = serialize_message(stance_message(stance, analysis.start_ns))
        back = stance_from_message(deserialize_message(wire, StanceKinetics))
        assert back.data_after_takeoff_s == expected
        for name in ("time_s", "angle_rad", "angular_velocity_rad_s", "moment_nm", "power_w"):
            np.testing.assert_array_equal(getattr(back.joints, name), getattr(stance.joints, name))
    assert stance_from_message(StanceKinetics()).data_after_takeoff_s is None
