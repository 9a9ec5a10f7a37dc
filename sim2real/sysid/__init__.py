"""The diagnosis: given a model and recordings that disagree, find, name and fit the missing physics.

Pipeline: ``recordings`` (files, validated) -> ``trajectory`` (model-order arrays) -> ``shooting``
(batched MJX segments) -> ``fit`` (Gauss-Newton) -> ``select`` (forward selection over
``candidates``, from the kind plug-ins) -> ``diagnose`` (driver, held-out guard) -> ``report``,
``export``. What a user imports is re-exported here (loaded on first use)::

    from sim2real.sysid import DiagnoseConfig, diagnose
"""
from __future__ import annotations

from sim2real._lazy import exports

# public name -> "module:attribute"
_EXPORTS = {
    "DiagnoseConfig": "sim2real.sysid.diagnose:DiagnoseConfig",
    "diagnose": "sim2real.sysid.diagnose:diagnose",
    "Recording": "sim2real.sysid.recordings:Recording",
    "RecordingError": "sim2real.sysid.recordings:RecordingError",
    "load_recording": "sim2real.sysid.recordings:load",
    "load_recordings": "sim2real.sysid.recordings:load_all",
    "save_csv": "sim2real.sysid.recordings:save_csv",
    "System": "sim2real.sysid.system:System",
    "ModelError": "sim2real.sysid.system:ModelError",
    "EFFECTS": "sim2real.sysid.candidates:EFFECTS",
    "ALL_EFFECTS": "sim2real.sysid.candidates:ALL_EFFECTS",
    "write_fitted_mjcf": "sim2real.sysid.export:write_fitted_mjcf",
}
__getattr__, __dir__, __all__ = exports(__name__, _EXPORTS)
