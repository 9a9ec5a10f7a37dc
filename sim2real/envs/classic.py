"""Parameter declarations shared by the small envs (pendulum, cartpole, arm, prismatic drive)."""
from __future__ import annotations

import jax.numpy as jnp
import mujoco

from sim2real.physics import catalog
from sim2real.physics.params import Param


def small_env_params(m: mujoco.MjModel, damping_unit: str = "Nm s/rad") -> list[Param]:
    """Body masses, joint damping, actuator gains and every effect on actuated joints/bodies."""
    joints = catalog.actuated_joints(m)
    damping = float(m.dof_damping[m.jnt_dofadr[joints[0]]])
    bodies = list(range(1, m.nbody))
    ps = [Param("joint_damping", damping, 0.0, max(100.0, 100 * damping), damping_unit,
                "viscous damping of the actuated joints", "joint_damping")]
    ps += catalog.body_mass_params(m, bodies)
    ps += catalog.actuator_gain_params(m, range(m.nu))
    ps += catalog.effect_params(m, joints, range(m.nu), bodies)
    return ps


def wrap_angle(x):
    return (x + jnp.pi) % (2 * jnp.pi) - jnp.pi


def tolerance(x, margin):
    """Smooth reward in (0, 1]: 1 at 0, 0.1 at ``|x| = margin`` (Gaussian, as dm_control)."""
    return jnp.exp(jnp.log(0.1) * jnp.square(x / margin))
