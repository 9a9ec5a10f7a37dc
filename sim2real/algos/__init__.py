"""Outer loops that learn the randomisation itself: UDR, LSDR/EPOpt, SimOpt, ES-MAML."""
from __future__ import annotations

from sim2real._lazy import exports

# public name -> "module:attribute"
_EXPORTS = {
    "DRConfig": "sim2real.algos.base:DRConfig",
    "DRSpace": "sim2real.algos.base:DRSpace",
    "build": "sim2real.algos.registry:build",
    "register": "sim2real.algos.registry:register",
    "UDR": "sim2real.algos.udr:UDR",
    "LSDR": "sim2real.algos.lsdr:LSDR",
    "ESMAML": "sim2real.algos.es_maml:ESMAML",
    "SimOpt": "sim2real.algos.simopt:SimOpt",
}
__getattr__, __dir__, __all__ = exports(__name__, _EXPORTS)
