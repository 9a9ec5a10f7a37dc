"""sim2real's envs in the tools users already have: Gymnasium (``gymnasium.py``: a vector env
and a single-env view, numpy at the boundary, batch on the device). Each adapter imports its
library only when used."""
from __future__ import annotations

from sim2real._lazy import exports

# public name -> "module:attribute"
_EXPORTS = {
    "GymnasiumEnv": "sim2real.interop.gymnasium:GymnasiumEnv",
    "GymnasiumVectorEnv": "sim2real.interop.gymnasium:GymnasiumVectorEnv",
}
__getattr__, __dir__, __all__ = exports(__name__, _EXPORTS)
