"""A joint spring a model leaves out (about the reference pose), added to the declared one."""
from __future__ import annotations

from sim2real.physics.kinds.base import JOINT, Kind, add_magnitude, coef, set_coef


class Stiffness(Kind):
    owns = ("stiffness",)
    attach = JOINT
    declares = {"stiffness": (0.0, 0.0, 1e5, "N/m|Nm/rad", "joint spring added to the nominal one, about the reference pose")}
    order = 56
    effect = "joint_stiffness"

    def apply(self, pm, z, get, f) -> None:
        for i, p in pm.spec.of_kind("stiffness"):
            f["jnt_stiffness"] = get("jnt_stiffness").at[p.index].add(z[i])

    def export(self, ctx, p, v) -> None:
        if v > 0:
            j = ctx.spec.joint(ctx.system.joints[p.index])
            j.stiffness = set_coef(j.stiffness, coef(j.stiffness) + v)

    def candidates(self, system, sc, add, target) -> None:
        jn = system.joints[target]
        if system.declared_stiffness(jn):
            return
        k = sc.force[target] / (0.5 * sc.range[target])
        add_magnitude(add, "joint_stiffness", jn, f"stiffness:{jn}", k, 3.0)
