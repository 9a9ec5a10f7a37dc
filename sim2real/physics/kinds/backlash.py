"""Backlash: a dead band between an actuator and its joint, crossed by the motor side's inertia
(the command path's last stage)."""
from __future__ import annotations

import jax.numpy as jnp
import mujoco
import numpy as np

from sim2real.physics.kinds.base import ACTUATOR, Kind, name_of, rows, take
from sim2real.physics.kinds.gain import is_servo, nominal_gain
from sim2real.physics.params import Param


def inertia_params(m: mujoco.MjModel, actuators, default: float = 1e-2) -> list[Param]:
    """``backlash_inertia:<act>``: the motor side's inertia crossing a backlash dead band (reflected
    to the joint); defaults to the joint's armature, or ``default`` where it has none (the
    effects library's fixed guess), so the default is neutral."""
    ps = []
    for a in actuators:
        j = int(m.actuator_trnid[a, 0])
        arm = float(m.dof_armature[m.jnt_dofadr[j]])
        slide = m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
        ps.append(Param(f"backlash_inertia:{name_of(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a)}", arm if arm > 0 else default,
                        1e-7, 1e4, "kg" if slide else "kg m^2", "inertia of the motor side crossing the backlash band",
                        "backlash_inertia", a))
    return ps


class Backlash(Kind):
    owns = ("backlash", "backlash_inertia")
    attach = ACTUATOR
    declares = {"backlash": (0.0, 0.0, 1.0, "m|rad", "dead band width between the actuator and its joint")}
    order = 61
    effect = "backlash"
    candidate_order = 64
    command_order = 30

    def command_setup(self, m, spec, cfg):
        acts = np.arange(m.nu)
        r = rows(spec, "backlash", acts)
        if not (r >= 0).any():
            return None
        joint = np.array([m.actuator_trnid[a, 0] for a in acts], np.int32)
        arm = np.array([m.dof_armature[m.jnt_dofadr[j]] for j in joint])
        return {
            "rows": r,
            # the motor side's inertia may be a parameter too (the diagnosis fits it); else the static guess
            "inertia_rows": rows(spec, "backlash_inertia", acts),
            "inertia": (np.full(m.nu, cfg.backlash_inertia) if cfg.backlash_inertia > 0 else np.where(arm > 0, arm, 1e-2)),
            "gain_rows": rows(spec, "actuator_gain", acts),
            "gain": np.array([nominal_gain(m, a) for a in acts]),
            "qpos": np.array([m.jnt_qposadr[j] for j in joint], np.int32),
            "servo": np.array([is_servo(m, a) for a in acts], bool),
        }

    def command_state(self, data, ctrl):
        """``(gap [nu], gap_vel [nu])``: the motor side's offset inside the band, and its rate."""
        nu = len(data["rows"])
        return jnp.zeros(nu), jnp.zeros(nu)

    def command(self, data, z, state, u, j, n, qpos, h):
        gap, gap_vel = state
        b = take(z, data["rows"])
        half = 0.5 * b
        q = qpos[data["qpos"]]
        # servo: the spring between target and joint acts only outside the band
        err = u - q
        servo_u = q + jnp.sign(err) * jnp.maximum(jnp.abs(err) - half, 0.0)
        # motor: torque reaches the joint only once the motor side has crossed the band
        gain = jnp.where(data["gain_rows"] >= 0, take(z, data["gain_rows"]), data["gain"])
        torque = gain * u
        inertia = jnp.where(data["inertia_rows"] >= 0, take(z, data["inertia_rows"], 1.0), data["inertia"])
        gv = gap_vel + h * torque / jnp.maximum(inertia, 1e-9)
        g = gap + h * gv
        hit_hi, hit_lo = g >= half, g <= -half
        engaged = (hit_hi & (torque > 0)) | (hit_lo & (torque < 0))
        motor_u = jnp.where(engaged, u, 0.0)
        on, servo = b > 0, data["servo"]
        gap = jnp.where(on & ~servo, jnp.clip(g, -half, half), gap)
        gap_vel = jnp.where(on & ~servo, jnp.where(hit_hi | hit_lo, 0.0, gv), gap_vel)
        return jnp.where(on, jnp.where(servo, servo_u, motor_u), u), (gap, gap_vel)

    def command_rows(self, data):
        return [int(r) for r in data["rows"] if r >= 0]

    def candidates(self, system, sc, add, target) -> None:
        m = system.mj
        an = system.actuators[target]
        j = int(m.actuator_trnid[target, 0])
        # the dead band's width and the inertia of the motor side that crosses it (a few percent
        # of the joint's own, unknown: fitted)
        slide = m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
        widths = np.geomspace(4e-5, 2e-3, 4) if slide else np.geomspace(0.004, 0.06, 4)
        J = float(sc.inertia[j]) if sc.inertia is not None else 1e-2
        add("backlash", an, [f"backlash:{an}", f"backlash_inertia:{an}"],
            [(w, f * J) for w in widths for f in (0.01, 0.1)], [float(widths[1]), 0.03 * J],
            [(0.25 * float(widths[0]), float(widths[-1])), (1e-4 * J, 2.0 * J)])
