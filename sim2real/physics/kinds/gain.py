"""Actuator gains: force per unit command (``gain``; a servo's Kp, with its stiffness bias) and a
servo's velocity gain (``kv``), as scalings of the actuator's declared gain/bias law."""
from __future__ import annotations

import mujoco
import numpy as np

from sim2real.physics.kinds.base import TURNING, Kind, actuator_joint, name_of
from sim2real.physics.params import Param


def is_servo(m: mujoco.MjModel, a: int) -> bool:
    """A position servo (gain fixed, bias affine in qpos): force = kp*ctrl - kp*q - kv*qdot."""
    return (m.actuator_gaintype[a] == mujoco.mjtGain.mjGAIN_FIXED
            and m.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_AFFINE
            and m.actuator_biasprm[a, 1] != 0)


def gear_size(m: mujoco.MjModel, a: int) -> float:
    """Actuator ``a``'s gear as one number: its first entry where MuJoCo reads no other (a hinge, a
    slide, a tendon), the whole vector's length where it is a direction (a site's wrench, a ball or
    free joint's axis). Why: a thruster's gear is "0 0 1 0 0 0.02" (thrust along the site's z,
    with its drag torque); its first entry, 0, made the gain's default 0, and the gain law,
    scaled by value / default, was scaled by 0 instead of 1: the drone flew without thrust."""
    g = np.asarray(m.actuator_gear[a], float)
    j = actuator_joint(m, a)
    multi = (int(m.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_SITE)
             or (j >= 0 and int(m.jnt_type[j]) in TURNING))
    return float(np.linalg.norm(g)) if multi else float(g[0])


def nominal_gain(m: mujoco.MjModel, a: int) -> float:
    """Actuator ``a``'s declared force per unit command: gear x gain (Kp for a position servo)."""
    return gear_size(m, a) * float(m.actuator_gainprm[a, 0])


def declare(m: mujoco.MjModel, actuators) -> list[Param]:
    """``gain:<act>``: torque per unit command for motors, Kp for position servos; ``kv:<act>`` for servos."""
    ps = []
    for a in actuators:
        an = name_of(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a)
        g = nominal_gain(m, a)
        ps.append(Param(f"gain:{an}", round(g, 6), 0.0, 100.0 * abs(g) + 1.0, "N|Nm per unit",
                        "actuator gain (gear x gain; Kp for position servos)", "actuator_gain", a))
        if is_servo(m, a) and m.actuator_biasprm[a, 2] != 0:
            kv = float(-m.actuator_biasprm[a, 2]) * gear_size(m, a)
            ps.append(Param(f"kv:{an}", round(kv, 6), 0.0, 100.0 * kv + 1.0, "N s/m|Nm s/rad",
                            "servo velocity gain", "actuator_kv", a))
    return ps


def gain_law_entries(m: mujoco.MjModel, kind: str, a: int) -> list[tuple[str, int]]:
    """The ``(field, column)`` entries of actuator ``a``'s declared gain/bias law that a ``gain:``
    (``kind`` "actuator_gain") or ``kv:`` ("actuator_kv") parameter scales by value / default.

    The gain, and with it a position-like servo's stiffness bias -kp*q (which must follow kp, or
    the servo's set point moves); ``kv`` scales the damping bias -kv*qdot. ``field`` is the MjSpec
    actuator attribute; the compiled model's is ``"actuator_" + field``. At the default value the
    law is exactly the declared one (``apply`` and ``export`` both use this).
    """
    if kind == "actuator_gain":
        return [("gainprm", 0)] + ([("biasprm", 1)] if m.actuator_biasprm[a, 1] != 0 else [])
    if kind == "actuator_kv":
        return [("biasprm", 2)]
    raise ValueError(f"not an actuator gain kind: {kind!r}")


class ActuatorGain(Kind):
    owns = ("actuator_gain", "actuator_kv")
    order = 60

    def apply(self, pm, z, get, f) -> None:
        m0 = pm.mx
        for kind in self.owns:
            for i, p in pm.spec.of_kind(kind):
                a, ratio = p.index, z[i] / p.default if p.default else z[i]
                for field, col in gain_law_entries(pm.mj, kind, a):
                    name = f"actuator_{field}"
                    f[name] = get(name).at[a, col].set(getattr(m0, name)[a, col] * ratio)

    def export(self, ctx, p, v) -> None:
        if v == p.default or not p.default:
            return
        a = ctx.spec.actuator(ctx.system.actuators[p.index])
        mj = ctx.system.mj
        for field, col in gain_law_entries(mj, p.kind, p.index):
            getattr(a, field)[col] = float(getattr(mj, f"actuator_{field}")[p.index, col]) * v / p.default
