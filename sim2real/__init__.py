"""sim2real: JAX-native, massively batched sim-to-real training and sim-vs-real diagnosis.

What a user imports (loaded on first use, so ``import sim2real`` is instant and has no side
effects)::

    import sim2real as s2r
    env = s2r.make("pendulum")                       # an MJX env with named physics (env.spec)
    z = env.z_of(**{"mass:pole": 1.2})               # a physics vector, bounds checked
    out = s2r.train(s2r.TrainConfig(env="pendulum", total_steps=200_000))
    d = s2r.diagnose(s2r.DiagnoseConfig(model="robot.xml", recordings=("run1.csv",)))

One side effect: on jaxlib 0.9, ``XLA_FLAGS`` gains ``--xla_cpu_use_fusion_emitters=false`` if JAX
has not started yet (an XLA CPU slowdown exponential in a kinematic chain's depth; ``_xla_cpu.py``).
"""
from __future__ import annotations

from sim2real import _xla_cpu
from sim2real._lazy import exports

_xla_cpu.configure()

__version__ = "0.1.0"

# public name -> "module:attribute"
_EXPORTS = {
    "make": "sim2real.envs:make",
    "env_names": "sim2real.envs:names",
    "Env": "sim2real.envs:Env",
    "EnvConfig": "sim2real.envs:EnvConfig",
    "Param": "sim2real.physics.params:Param",
    "ParamSpec": "sim2real.physics.params:ParamSpec",
    "PPO": "sim2real.rl.ppo:PPO",
    "PPOConfig": "sim2real.rl.ppo:PPOConfig",
    "DRConfig": "sim2real.algos.base:DRConfig",
    "TrainConfig": "sim2real.training.runs:TrainConfig",
    "train": "sim2real.training.driver:train",
    "load_policy": "sim2real.training.runs:load_policy",
    "DiagnoseConfig": "sim2real.sysid.diagnose:DiagnoseConfig",
    "diagnose": "sim2real.sysid.diagnose:diagnose",
    "load_recordings": "sim2real.sysid.recordings:load_all",
    "Recording": "sim2real.sysid.recordings:Recording",
    "ConfigError": "sim2real.common.config:ConfigError",
}
__getattr__, __dir__, __all__ = exports(__name__, _EXPORTS)
__all__ = __all__ + ["__version__"]
