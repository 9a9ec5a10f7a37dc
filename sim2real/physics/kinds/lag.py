"""Motor lag: a first-order filter on the actuator command (the command path's second stage);
written into MJCF as MuJoCo's exact first-order filter."""
from __future__ import annotations

import jax.numpy as jnp
import mujoco
import numpy as np

from sim2real.physics.kinds.base import ACTUATOR, Kind, rows, take


class MotorLag(Kind):
    owns = ("motor_lag",)
    attach = ACTUATOR
    declares = {"motor_lag": (0.0, 0.0, 1.0, "s", "time constant of a first-order lag on the actuator command")}
    order = 63
    effect = "motor_lag"
    candidate_order = 60.5  # searched before the other actuator effects
    command_order = 20

    def command_setup(self, m, spec, cfg):
        r = rows(spec, "motor_lag", np.arange(m.nu))
        return {"rows": r} if (r >= 0).any() else None

    def command_state(self, data, ctrl):
        """``[nu]`` the filter's output."""
        return jnp.asarray(ctrl, jnp.float32) + jnp.zeros(len(data["rows"]))

    def command(self, data, z, lag, u, j, n, qpos, h, qvel=None):
        # exact discretisation over the sub-step
        tau = take(z, data["rows"])
        alpha = 1.0 - jnp.exp(-h / jnp.maximum(tau, 1e-9))
        u = jnp.where(tau > 0, lag + alpha * (u - lag), u)
        return u, u

    def command_rows(self, data):
        return [int(r) for r in data["rows"] if r >= 0]

    def export(self, ctx, p, v) -> None:
        # (an actuator with dynamics of its own cannot take a second filter: <numeric> only)
        if v > 0 and ctx.system.mj.actuator_dyntype[p.index] == 0:
            a = ctx.spec.actuator(ctx.system.actuators[p.index])
            a.dyntype = mujoco.mjtDyn.mjDYN_FILTEREXACT
            a.dynprm[0] = v
            a.actlimited = 0
        elif v > 0:
            ctx.only_numeric(p.name, "the actuator already has activation dynamics; MuJoCo takes one filter")

    def candidates(self, system, sc, add, target) -> None:
        an = system.actuators[target]
        taus = np.geomspace(max(0.4 * sc.dt, 0.002), 0.25, 7)
        add("motor_lag", an, [f"motor_lag:{an}"], [(t,) for t in taus], [float(taus[2])],
            [(0.25 * float(taus[0]), 0.25)])
