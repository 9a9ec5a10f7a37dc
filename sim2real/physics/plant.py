"""The simulated plant: one MuJoCo model, its named physics parameters, and how both act in MJX.

The envs step it (``envs/base.py``) and the diagnosis fits it (``sysid/system.py``): the same
``PhysicsModel.apply`` (parameters -> ``mjx.Model``), the same effects library (the command path,
velocity-dependent forces, sensing) and the same ``stepper.advance``, so a diagnosis of an env's
own MJCF describes exactly the system that env trains on (``algos/from_diagnosis.py``).
"""
from __future__ import annotations

import jax
import mujoco
from sim2real._mjx import mjx

from sim2real.physics import catalog
from sim2real.physics.effects import Effects, EffectsConfig
from sim2real.physics.model_apply import PhysicsModel
from sim2real.physics.params import Param, ParamSpec


class Plant:
    """``Plant(m, params, max_delay, coulomb_eps, joint_damping_dofs=())``.

    Args:
      m: the native model (its ``opt`` already as it should run: timestep, integrator, solver).
      params: the model's own parameters (masses, sizes, gains, effects ...); the parameters every
        plant has (``catalog.common_params``: delay, gravity, observation noise) are appended.
      max_delay: length of the action-delay line (control steps or samples).
      coulomb_eps: velocity scale (m/s or rad/s) of the smooth Coulomb friction model.
      joint_damping_dofs: dofs that the global ``joint_damping`` parameter sets (envs).

    Attributes:
      spec: every parameter, ``[P]`` physics vectors index it.
      physics: ``PhysicsModel`` (``apply(z) -> mjx.Model``).
      mj: the native model MJX runs (``physics.mj``: saturation clamps added).
      effects: the effects library on this model.
      data0: a template ``mjx.Data`` (``replace(qpos=..., qvel=...)`` starts a trajectory).
    """

    def __init__(self, m: mujoco.MjModel, params: list[Param], max_delay: int, coulomb_eps: float,
                 joint_damping_dofs=()):
        self.spec = ParamSpec(list(params) + catalog.common_params(m, max_delay))
        self.physics = PhysicsModel(m, self.spec, joint_damping_dofs)
        self.mj = self.physics.mj
        self.effects = Effects(self.mj, self.spec, EffectsConfig(max_delay=max_delay, coulomb_eps=coulomb_eps))
        # this process's own device: with several processes (jax.distributed) JAX's first device
        # may belong to another one, which MJX's default would pick
        self.data0 = mjx.make_data(self.physics.mx, device=jax.local_devices()[0])
