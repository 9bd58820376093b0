"""Lab data to contract recordings: C3D (ezc3d), OpenSim TRC/MOT, force-only text.

Entry points: :func:`import_c3d`, :func:`import_opensim`, :func:`import_force_only`
(all return a :class:`~hop_impedance.recording.Recording` in the contract frame
and SI units) and :func:`write_c3d` (the reverse, for round trips). See
``docs/importing.md``.
"""

from hop_impedance.importers.c3d_export import write_c3d
from hop_impedance.importers.c3d_import import import_c3d
from hop_impedance.importers.force_only_import import FORCE_ONLY_LIMITS, import_force_only
from hop_impedance.importers.marker_mapping import MissingMarkersError, available_mappings, load_marker_mapping
from hop_impedance.importers.opensim_import import import_opensim

__all__ = [
    "FORCE_ONLY_LIMITS",
    "MissingMarkersError",
    "available_mappings",
    "import_c3d",
    "import_force_only",
    "import_opensim",
    "load_marker_mapping",
    "write_c3d",
]
