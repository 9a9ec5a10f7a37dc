"""Declared joint damping: per joint (``dof_damping``, the diagnosis' nominal parameter), or one value
(``joint_damping``) or multiplier (``joint_damping_scale``) for the dofs an env names."""
from __future__ import annotations

from sim2real.physics.kinds.base import Kind, joint_dofs, set_coef


class Damping(Kind):
    owns = ("joint_damping", "joint_damping_scale", "dof_damping")
    order = 50

    def apply(self, pm, z, get, f) -> None:
        dofs = pm.joint_damping_dofs
        for i, _ in pm.spec.of_kind("joint_damping"):
            if len(dofs):
                f["dof_damping"] = get("dof_damping").at[dofs].set(z[i])
        for i, _ in pm.spec.of_kind("joint_damping_scale"):
            if len(dofs):
                f["dof_damping"] = get("dof_damping").at[dofs].multiply(z[i])
        for i, p in pm.spec.of_kind("dof_damping"):
            f["dof_damping"] = get("dof_damping").at[joint_dofs(pm.mj, p.index)].set(z[i])

    def export(self, ctx, p, v) -> None:
        if p.kind == "dof_damping":
            j = ctx.spec.joint(ctx.system.joints[p.index])
            j.damping = set_coef(j.damping, v)
