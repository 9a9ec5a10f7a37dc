"""Viscous damping a model leaves out: added to the joint's declared damping."""
from __future__ import annotations

from sim2real.physics.kinds.base import JOINT, Kind, add_magnitude, coef, joint_dofs, set_coef


class Viscous(Kind):
    owns = ("viscous",)
    attach = JOINT
    declares = {"viscous": (0.0, 0.0, 1e4, "N s/m|Nm s/rad", "viscous damping added to the joint's nominal damping")}
    order = 55
    effect = "viscous_damping"

    def apply(self, pm, z, get, f) -> None:
        for i, p in pm.spec.of_kind("viscous"):
            f["dof_damping"] = get("dof_damping").at[joint_dofs(pm.mj, p.index)].add(z[i])

    def export(self, ctx, p, v) -> None:
        if v > 0:
            j = ctx.spec.joint(ctx.system.joints[p.index])
            j.damping = set_coef(j.damping, coef(j.damping) + v)

    def candidates(self, system, sc, add, target) -> None:
        jn = system.joints[target]
        if system.declared_damping(jn):  # a declared damping is re-fitted as a nominal parameter
            return
        c = sc.force[target] / sc.speed[target]
        add_magnitude(add, "viscous_damping", jn, f"viscous:{jn}", c, 3.0)
