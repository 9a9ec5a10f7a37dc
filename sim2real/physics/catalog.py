"""Builders for the named parameters every env exposes.

Nominal parameters (masses, sizes, friction, damping, gains, gravity) describe the model an
engineer writes; effect parameters (Coulomb friction, backlash, delay, ...) describe physics a
nominal model usually leaves out. Effects default to their neutral value, so an env with all
defaults *is* the nominal model, bit for bit (``tests/test_effects.py``).
"""
from __future__ import annotations

import mujoco
import numpy as np

from sim2real.physics import kinds
from sim2real.physics.kinds.armature import params as armature_params  # noqa: F401
from sim2real.physics.kinds.backlash import motor_side_params as backlash_motor_side_params  # noqa: F401
from sim2real.physics.kinds.base import actuator_is_linear, name_of, unit_for
from sim2real.physics.kinds.contact import body_params as contact_friction_params  # noqa: F401
from sim2real.physics.kinds.gain import declare as actuator_gain_params  # noqa: F401
from sim2real.physics.kinds.gain import gain_law_entries, is_servo  # noqa: F401
from sim2real.physics.kinds.mass import declare as body_mass_params  # noqa: F401
from sim2real.physics.kinds.payload import link_axis  # noqa: F401
from sim2real.physics.kinds.payload import position_params as payload_position_params  # noqa: F401
from sim2real.physics.params import Param

_JOINT, _ACT, _BODY, _GEOM = (
    mujoco.mjtObj.mjOBJ_JOINT,
    mujoco.mjtObj.mjOBJ_ACTUATOR,
    mujoco.mjtObj.mjOBJ_BODY,
    mujoco.mjtObj.mjOBJ_GEOM,
)


def _effects_on(attach: str) -> dict:
    return {kind: entry for k in kinds.attached(attach) for kind, entry in k.declares.items()}


def _declared(m: mujoco.MjModel, i: int, kind: str, entry: tuple) -> tuple:
    """``entry`` of ``kind`` as its plug-in declares it on object ``i`` (``Kind.declared``)."""
    return kinds.owner(kind).declared(m, i, kind, entry)


# Effect parameters per target: kind -> (default, low, high, unit, doc), from the kind plug-ins
# (``physics/kinds/``); the library the diagnosis searches comes from the same plug-ins.
JOINT_EFFECTS = _effects_on(kinds.JOINT)
ACTUATOR_EFFECTS = _effects_on(kinds.ACTUATOR)
BODY_EFFECTS = _effects_on(kinds.BODY)


def actuated_joints(m: mujoco.MjModel) -> list[int]:
    """Joints driven by an actuator (transmission type joint), in actuator order."""
    out = []
    for a in range(m.nu):
        if m.actuator_trntype[a] != mujoco.mjtTrn.mjTRN_JOINT:
            raise ValueError("only joint transmissions are supported for actuator effects")
        j = int(m.actuator_trnid[a, 0])
        if j not in out:
            out.append(j)
    return out


def effect_params(m: mujoco.MjModel, joints, actuators, bodies) -> list[Param]:
    """Effect parameters for the given joint / actuator / body ids (all neutral by default)."""
    ps = []
    for table, ids, obj in ((JOINT_EFFECTS, joints, _JOINT), (ACTUATOR_EFFECTS, actuators, _ACT),
                            (BODY_EFFECTS, bodies, _BODY)):
        for i in ids:
            name = name_of(m, obj, i)
            slide = (m.jnt_type[i] == mujoco.mjtJoint.mjJNT_SLIDE if obj == _JOINT
                     else actuator_is_linear(m, i) if obj == _ACT else False)
            for kind, entry in table.items():
                d, lo, hi, unit, doc = _declared(m, i, kind, entry)
                ps.append(Param(f"{kind}:{name}", d, lo, hi, unit_for(unit, slide), doc, kind, i))
    return ps


def common_params(m: mujoco.MjModel, max_delay: int) -> list[Param]:
    g = float(-m.opt.gravity[2])
    return [
        Param("gravity", round(g, 6), 0.0, 30.0, "m/s^2", "gravity magnitude along -z", "gravity"),
        Param("action_delay", 0.0, 0.0, float(max_delay), "steps",
              "delay of the applied action in control steps (fractional steps interpolate)", "action_delay"),
        Param("obs_noise", 0.0, 0.0, 10.0, "obs units", "std of white noise added to every observation", "obs_noise"),
    ]


def names(m: mujoco.MjModel, obj) -> list[str]:
    """Names of every joint / actuator / body / geom (``obj``), in id order ("" where unnamed)."""
    n = {_JOINT: m.njnt, _ACT: m.nu, _BODY: m.nbody, _GEOM: m.ngeom}[obj]
    return [mujoco.mj_id2name(m, obj, k) or "" for k in range(n)]


def lookup(m: mujoco.MjModel, obj, name: str, what: str) -> int:
    i = mujoco.mj_name2id(m, obj, name)
    if i < 0:
        known = names(m, obj)
        raise KeyError(f"unknown {what} '{name}'; the model has: {', '.join(k for k in known if k)}")
    return i


def dofs_of_joints(m: mujoco.MjModel, joints) -> np.ndarray:
    return np.array([m.jnt_dofadr[j] for j in joints], np.int32)
