"""sim2real's envs in the tools users already have: Gymnasium (``gymnasium.py``: a vector env
and a single-env view, numpy at the boundary, batch on the device) and Brax (``brax.py``: a
``brax.envs.Env`` whose physics is redrawn at every reset, for Brax's PPO / SAC); and the other
way, a MuJoCo Playground task as a sim2real env (``sim2real/envs/playground.py``: ``make("playground:CheetahRun")``,
its MjModel read into a ParamSpec). Each adapter imports its library only when used."""
from __future__ import annotations

from sim2real._lazy import exports

# public name -> "module:attribute"
_EXPORTS = {
    "GymnasiumEnv": "sim2real.interop.gymnasium:GymnasiumEnv",
    "GymnasiumVectorEnv": "sim2real.interop.gymnasium:GymnasiumVectorEnv",
    "BraxEnv": "sim2real.interop.brax:BraxEnv",
    "brax_wrap_for_training": "sim2real.interop.brax:wrap_for_training",
    "PlaygroundEnv": "sim2real.envs.playground:PlaygroundEnv",
}
__getattr__, __dir__, __all__ = exports(__name__, _EXPORTS)
