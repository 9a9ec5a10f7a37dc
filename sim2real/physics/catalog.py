"""Builders for the named parameters every env exposes.

Nominal parameters (masses, sizes, friction, damping, gains, gravity) describe the model an
engineer writes; effect parameters (Coulomb friction, backlash, delay, ...) describe physics a
nominal model usually leaves out. Effects default to their neutral value, so an env with all
defaults *is* the nominal model, bit for bit (``tests/test_effects.py``).
"""
from __future__ import annotations

import mujoco
import numpy as np

from sim2real.physics.params import Param

_JOINT, _ACT, _BODY, _GEOM = (
    mujoco.mjtObj.mjOBJ_JOINT,
    mujoco.mjtObj.mjOBJ_ACTUATOR,
    mujoco.mjtObj.mjOBJ_BODY,
    mujoco.mjtObj.mjOBJ_GEOM,
)

# Effect kinds per target, their neutral value, bounds, unit and meaning. The library the
# diagnosis tool searches is built from the same table (sysid/candidates.py).
JOINT_EFFECTS = {
    # kind: (default, low, high, unit, doc)
    "coulomb": (0.0, 0.0, 1e4, "N|Nm", "Coulomb friction level Fc opposing joint motion"),
    "coulomb_asym": (0.0, -1.0, 1.0, "-", "asymmetry a: Fc(1+a) for positive, Fc(1-a) for negative velocity"),
    "stribeck": (0.0, 0.0, 1e4, "N|Nm", "extra breakaway friction Fs at zero velocity (Stribeck)"),
    "stribeck_vel": (0.1, 1e-4, 1e2, "m/s|rad/s", "Stribeck velocity vs: breakaway term decays as exp(-(v/vs)^2)"),
    "viscous": (0.0, 0.0, 1e4, "N s/m|Nm s/rad", "viscous damping added to the joint's nominal damping"),
    "stiffness": (0.0, 0.0, 1e5, "N/m|Nm/rad", "joint spring added to the nominal one, about the reference pose"),
    "sensor_offset": (0.0, -10.0, 10.0, "m|rad", "constant offset added to the measured joint position"),
    "sensor_noise": (0.0, 0.0, 1.0, "m|rad", "std of white noise added to the measured joint position"),
}
ACTUATOR_EFFECTS = {
    "backlash": (0.0, 0.0, 1.0, "m|rad", "dead band width between the actuator and its joint"),
    "saturation": (0.0, 0.0, 1e5, "N|Nm", "actuator force limit (0 = no limit)"),
    "motor_lag": (0.0, 0.0, 1.0, "s", "time constant of a first-order lag on the actuator command"),
}
BODY_EFFECTS = {
    "payload": (0.0, 0.0, 1e3, "kg", "point mass at the body's payload_<body> site (else its centre of mass)"),
}


def name_of(m: mujoco.MjModel, obj, i: int) -> str:
    n = mujoco.mj_id2name(m, obj, i)
    if not n:
        raise ValueError(f"object {obj} #{i} has no name; name every joint/actuator/body/geom you randomise")
    return n


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
    for j in joints:
        jn = name_of(m, _JOINT, j)
        slide = m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
        for kind, (d, lo, hi, unit, doc) in JOINT_EFFECTS.items():
            unit = unit.split("|")[0 if slide else -1]
            ps.append(Param(f"{kind}:{jn}", d, lo, hi, unit, doc, kind, j))
    for a in actuators:
        an = name_of(m, _ACT, a)
        for kind, (d, lo, hi, unit, doc) in ACTUATOR_EFFECTS.items():
            j = int(m.actuator_trnid[a, 0])
            slide = m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
            unit = unit.split("|")[0 if slide else -1]
            ps.append(Param(f"{kind}:{an}", d, lo, hi, unit, doc, kind, a))
    for b in bodies:
        bn = name_of(m, _BODY, b)
        for kind, (d, lo, hi, unit, doc) in BODY_EFFECTS.items():
            ps.append(Param(f"{kind}:{bn}", d, lo, hi, unit, doc, kind, b))
    return ps


def link_axis(m: mujoco.MjModel, b: int) -> tuple[np.ndarray, np.ndarray, float] | None:
    """``(anchor, unit direction, length)`` of a body hinged to its parent: from the joint axis's
    point through the centre of mass (body frame); None when the body has no hinge or its centre
    of mass sits on the axis (a payload there is only a mass change)."""
    if m.body_jntnum[b] != 1 or m.jnt_type[m.body_jntadr[b]] != mujoco.mjtJoint.mjJNT_HINGE:
        return None
    j = m.body_jntadr[b]
    anchor = np.asarray(m.jnt_pos[j], float)
    axis = np.asarray(m.jnt_axis[j], float)
    r = np.asarray(m.body_ipos[b], float) - anchor
    r = r - axis * np.dot(r, axis)  # the part perpendicular to the axis is what a payload acts through
    length = float(np.linalg.norm(r))
    if length < 1e-4:
        return None
    return anchor, r / length, length


def payload_position_params(m: mujoco.MjModel, bodies) -> list[Param]:
    """``payload_r:<body>``: distance of a payload from the joint axis along the link (through the
    centre of mass), for hinged bodies; the payload sits at the link's far end (twice the centre
    of mass distance, the tip of a uniform link) by default."""
    ps = []
    for b in bodies:
        ax = link_axis(m, b)
        if ax is None:
            continue
        length = ax[2]
        ps.append(Param(f"payload_r:{name_of(m, _BODY, b)}", round(2 * length, 6), 0.0, round(4 * length, 6), "m",
                        "distance of the payload from the joint axis, along the link", "payload_r", b))
    return ps


def backlash_inertia_params(m: mujoco.MjModel, actuators, default: float = 1e-2) -> list[Param]:
    """``backlash_inertia:<act>``: the motor side's inertia crossing a backlash dead band (reflected
    to the joint); defaults to the joint's armature, or ``default`` where it has none (the
    effects library's fixed guess), so the default is neutral."""
    ps = []
    for a in actuators:
        j = int(m.actuator_trnid[a, 0])
        arm = float(m.dof_armature[m.jnt_dofadr[j]])
        slide = m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
        ps.append(Param(f"backlash_inertia:{name_of(m, _ACT, a)}", arm if arm > 0 else default, 1e-7, 1e4,
                        "kg" if slide else "kg m^2", "inertia of the motor side crossing the backlash band",
                        "backlash_inertia", a))
    return ps


def body_mass_params(m: mujoco.MjModel, bodies) -> list[Param]:
    ps = []
    for b in bodies:
        mass = float(m.body_mass[b])
        ps.append(Param(f"mass:{name_of(m, _BODY, b)}", round(mass, 6), 1e-3 * mass, 1e3 * mass, "kg",
                        "body mass (inertia scaled with it)", "body_mass", b))
    return ps


def actuator_gain_params(m: mujoco.MjModel, actuators) -> list[Param]:
    """``gain:<act>``: torque per unit command for motors, Kp for position servos; ``kv:<act>`` for servos."""
    ps = []
    for a in actuators:
        an = name_of(m, _ACT, a)
        g = float(m.actuator_gear[a, 0] * m.actuator_gainprm[a, 0])
        ps.append(Param(f"gain:{an}", round(g, 6), 0.0, 100.0 * abs(g) + 1.0, "N|Nm per unit",
                        "actuator gain (gear x gain; Kp for position servos)", "actuator_gain", a))
        if is_servo(m, a) and m.actuator_biasprm[a, 2] != 0:
            kv = float(-m.actuator_biasprm[a, 2] * m.actuator_gear[a, 0])
            ps.append(Param(f"kv:{an}", round(kv, 6), 0.0, 100.0 * kv + 1.0, "N s/m|Nm s/rad",
                            "servo velocity gain", "actuator_kv", a))
    return ps


def gain_law_entries(m: mujoco.MjModel, kind: str, a: int) -> list[tuple[str, int]]:
    """The ``(field, column)`` entries of actuator ``a``'s declared gain/bias law that a ``gain:``
    (``kind`` "actuator_gain") or ``kv:`` ("actuator_kv") parameter scales by value / default.

    The gain, and with it a position-like servo's stiffness bias -kp*q (which must follow kp, or
    the servo's set point moves); ``kv`` scales the damping bias -kv*qdot. ``field`` is the MjSpec
    actuator attribute; the compiled model's is ``"actuator_" + field``. At the default value the
    law is exactly the declared one (``PhysicsModel.apply`` and ``export`` both use this).
    """
    if kind == "actuator_gain":
        return [("gainprm", 0)] + ([("biasprm", 1)] if m.actuator_biasprm[a, 1] != 0 else [])
    if kind == "actuator_kv":
        return [("biasprm", 2)]
    raise ValueError(f"not an actuator gain kind: {kind!r}")


def is_servo(m: mujoco.MjModel, a: int) -> bool:
    """A position servo (gain fixed, bias affine in qpos): force = kp*ctrl - kp*q - kv*qdot."""
    return (m.actuator_gaintype[a] == mujoco.mjtGain.mjGAIN_FIXED
            and m.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_AFFINE
            and m.actuator_biasprm[a, 1] != 0)


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
