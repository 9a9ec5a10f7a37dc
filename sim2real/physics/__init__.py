"""Named physics parameters with bounds, their kinds (plug-ins), ``PhysicsModel.apply`` and the effects library."""
from __future__ import annotations

from sim2real._lazy import exports

# public name -> "module:attribute"
_EXPORTS = {
    "Param": "sim2real.physics.params:Param",
    "ParamSpec": "sim2real.physics.params:ParamSpec",
    "Subspace": "sim2real.physics.params:Subspace",
    "clip": "sim2real.physics.params:clip",
    "PhysicsModel": "sim2real.physics.model_apply:PhysicsModel",
    "to_mjmodel": "sim2real.physics.model_apply:to_mjmodel",
    "Effects": "sim2real.physics.effects:Effects",
    "EffectsConfig": "sim2real.physics.effects:EffectsConfig",
    "Kind": "sim2real.physics.kinds.base:Kind",
    "all_kinds": "sim2real.physics.kinds:all_kinds",
}
__getattr__, __dir__, __all__ = exports(__name__, _EXPORTS)
