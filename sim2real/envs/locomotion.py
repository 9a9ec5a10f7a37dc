"""Shared pieces of the planar locomotion envs (hopper, halfcheetah), Gymnasium-v5 style."""
from __future__ import annotations

import jax
import jax.numpy as jnp
import mujoco

from sim2real.physics import catalog, massprops
from sim2real.physics.params import Param


def locomotion_params(m: mujoco.MjModel, torso_geom: str, damping_scale: bool = False) -> list[Param]:
    """The LSDR context (torso size, density, friction, joint damping) + masses, gains, effects.

    ``friction`` sets the sliding friction of every robot geom that collides with the floor
    (the hopper's foot; all of the cheetah's geoms). ``damping_scale`` makes the damping
    parameter a multiplier (the cheetah's joints have different nominal dampings).
    """
    tg = catalog.lookup(m, mujoco.mjtObj.mjOBJ_GEOM, torso_geom, "geom")
    act_joints = catalog.actuated_joints(m)
    touching = [g for g in range(m.ngeom) if m.geom_bodyid[g] > 0 and m.geom_contype[g] > 0]
    density = round(massprops.describe_body(m, int(m.geom_bodyid[tg])).density, 3)
    ps = [
        Param("torso_size", float(m.geom_size[tg, 0]), 0.001, 0.5, "m",
              "torso capsule radius (mass and inertia follow)", "geom_radius", tg),
        Param("density", density, 1.0, 2e4, "kg/m^3", "density of every body", "density"),
        Param("friction", float(m.geom_friction[touching[0], 0]), 0.0, 10.0, "-",
              "sliding friction of the robot geoms touching the floor", "geom_friction", -1),
    ]
    if damping_scale:
        ps.append(Param("damping_scale", 1.0, 0.0, 100.0, "-",
                        "multiplier on the actuated joints' nominal damping", "joint_damping_scale"))
    else:
        damping = float(m.dof_damping[m.jnt_dofadr[act_joints[0]]])
        ps.append(Param("joint_damping", damping, 0.0, 100.0, "Nm s/rad",
                        "damping of the actuated joints", "joint_damping"))
    bodies = list(range(1, m.nbody))
    ps += catalog.body_mass_params(m, bodies)
    ps += catalog.actuator_gain_params(m, range(m.nu))
    ps += catalog.effect_params(m, act_joints, range(m.nu), bodies)
    return ps


def uniform_reset(key, qpos0, nv, scale):
    k1, k2 = jax.random.split(key)
    qpos = qpos0 + jax.random.uniform(k1, qpos0.shape, minval=-scale, maxval=scale)
    qvel = jax.random.uniform(k2, (nv,), minval=-scale, maxval=scale)
    return qpos, qvel


def forward_obs(qpos, qvel, clip_vel=10.0):
    """Gymnasium v5: positions without rootx, velocities (the hopper clips them to +-10)."""
    if clip_vel:
        qvel = jnp.clip(qvel, -clip_vel, clip_vel)
    return jnp.concatenate([qpos[1:], qvel])
