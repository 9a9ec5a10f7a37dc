"""Action delay, in control steps (fractional steps are exact): the first stage of the command path."""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from sim2real.physics.kinds.base import Kind


class ActionDelay(Kind):
    owns = ("action_delay",)
    order = 70
    effect = "action_delay"
    command_order = 10

    def command_setup(self, m, spec, cfg):
        if "action_delay" not in spec:
            return None
        return {"row": spec.index("action_delay"), "length": cfg.max_delay + 2, "nu": m.nu}

    def command_state(self, data, ctrl):
        """``[D + 2, nu]`` past commands, newest first."""
        return jnp.broadcast_to(ctrl, (data["length"], data["nu"]))

    def push(self, data, buf, ctrl):
        return jnp.concatenate([ctrl[None], buf[:-1]], axis=0)

    def command(self, data, z, buf, u, j, n, qpos, h, qvel=None):
        """The command applied during sub-step ``j`` of ``n``.

        A delay of ``d`` control steps (fractional allowed) shifts the piecewise-constant command
        by ``d``; sub-step ``j`` spans ``[j/n, (j+1)/n)`` of the step, so it sees the shifted
        command averaged over that span -- at most two neighbouring commands, weighted by how
        much of the span each covers. Exact for any ``d`` and ``n``; with ``n = 1`` it is the
        blend ``(1 - f) u[k] + f u[k+1]`` of the fractional part ``f``.
        """
        d = z[data["row"]]
        a = j / n - d                        # start of the span, in steps, relative to this step
        ka = jnp.floor(a)
        w = jnp.clip((ka + 1.0 - a) * n, 0.0, 1.0)   # share of the span inside step ka
        i = jnp.clip(-ka, 0, buf.shape[0] - 1).astype(jnp.int32)
        newer = jnp.maximum(i - 1, 0)
        delayed = w * buf[i] + (1.0 - w) * buf[newer]
        return jnp.where(d > 0, delayed, u), buf

    def command_rows(self, data):
        return [data["row"]]

    def export(self, ctx, p, v) -> None:
        # MuJoCo >= 3.4 delays an actuator's control through a history buffer of ``nsample``
        # physics steps; ``interp="linear"`` makes a delay that is not a whole number of them exact
        # for the zero-order-held commands the fit assumed
        if v <= 0:
            return
        seconds = v * ctx.system.h * ctx.system.substeps
        step = float(ctx.spec.option.timestep)
        for an in ctx.system.actuators:
            a = ctx.spec.actuator(an)
            a.delay = float(a.delay) + seconds
            a.nsample = max(int(a.nsample), int(np.ceil(a.delay / step)) + 2)
            a.interp = 1
        ctx.native(p.name, f"{seconds * 1e3:.4g} ms on every actuator (its delay, nsample, interp='linear')")

    def candidates(self, system, sc, add, target) -> None:
        if not system.mj.nu:
            return
        pts = [d for d in (0.4, 1.0, 2.0, 3.5, 6.0, 10.0, 17.0, 28.0, 45.0, 70.0) if d <= sc.max_delay - 1]
        add("action_delay", "", ["action_delay"], [(d,) for d in pts], [1.0], [(0.1, float(max(pts)))])
