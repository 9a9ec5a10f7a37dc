"""Actuator saturation: a force limit (0 = none), as MuJoCo's own ``forcerange``."""
from __future__ import annotations

import copy

import jax.numpy as jnp

from sim2real.physics.kinds.base import ACTUATOR, Kind

_NO_LIMIT = 1e30  # force clamp that never binds: exactly neutral


class Saturation(Kind):
    owns = ("saturation",)
    attach = ACTUATOR
    declares = {"saturation": (0.0, 0.0, 1e5, "N|Nm", "actuator force limit (0 = no limit)")}
    order = 62
    effect = "actuator_saturation"

    def prepare(self, m, spec):
        if not spec.of_kind("saturation"):
            return m
        # MJX fixes at put_model time which actuators clamp their force; give every actuator the
        # clamp with a range no force reaches, so per-env saturation is a traced value.
        m = copy.copy(m)
        free = m.actuator_forcelimited == 0
        m.actuator_forcerange[free] = [-_NO_LIMIT, _NO_LIMIT]
        m.actuator_forcelimited[:] = 1
        return m

    def apply(self, pm, z, get, f) -> None:
        m0 = pm.mx
        for i, p in pm.spec.of_kind("saturation"):
            a, s = p.index, z[i]
            on = s > 0
            f["actuator_forcerange"] = get("actuator_forcerange").at[a].set(
                jnp.where(on, jnp.stack([-s, s]), m0.actuator_forcerange[a]))

    def export(self, ctx, p, v) -> None:
        if v > 0:
            a = ctx.spec.actuator(ctx.system.actuators[p.index])
            a.forcelimited = 1
            a.forcerange = [-v, v]

    def candidates(self, system, sc, add, target) -> None:
        f = sc.act_force[target]
        add("actuator_saturation", system.actuators[target], [f"saturation:{system.actuators[target]}"],
            [(q * f,) for q in (0.2, 0.32, 0.5, 0.75)], [0.2 * f], [(0.2 * f, 1.0 * f)])
