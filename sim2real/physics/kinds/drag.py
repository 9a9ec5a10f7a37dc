"""Quadratic (aerodynamic, fluid) drag on a joint: force ``-c v |v|``.

The example of adding an effect as one file: declared on every joint, neutral at ``c = 0``,
simulated as the damping ``c |v|`` for the sub-step (implicit in MuJoCo's integrator, as Coulomb
friction is), written into MJCF as MuJoCo's own quadratic damping term (the second coefficient of
a joint's ``damping``: force ``-(d0 + d1 |v|) v``, MuJoCo >= 3.4), and offered to the diagnosis
as ``quadratic_drag`` when asked for (``effects=[..., quadratic_drag]``; not in the default
search, whose thresholds were tuned without it).
"""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from sim2real.physics.kinds.base import JOINT, Kind, add_magnitude, coef, rows, set_coef, take


class QuadraticDrag(Kind):
    owns = ("drag",)
    attach = JOINT
    declares = {"drag": (0.0, 0.0, 1e5, "N s^2/m^2|Nm s^2/rad^2", "quadratic drag c: force -c v|v|")}
    order = 58
    effect = "quadratic_drag"
    default_candidate = False

    def damping_setup(self, m, spec, cfg):
        joints = [p.index for _, p in spec.of_kind("drag")]
        if not joints:
            return None
        return np.array([m.jnt_dofadr[j] for j in joints], np.int32), rows(spec, "drag", joints)

    def damping(self, data, z, qvel):
        c = take(z, data)
        return jnp.where(c > 0, c * jnp.abs(qvel), 0.0)

    def export(self, ctx, p, v) -> None:
        if v > 0:
            j = ctx.spec.joint(ctx.system.joints[p.index])
            j.damping = set_coef(j.damping, coef(j.damping, 1) + v, k=1)

    def candidates(self, system, sc, add, target) -> None:
        jn = system.joints[target]
        c = sc.force[target] / sc.speed[target] ** 2  # the force it takes at the joint's RMS speed
        add_magnitude(add, "quadratic_drag", jn, f"drag:{jn}", c, 3.0)
