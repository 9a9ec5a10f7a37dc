"""A joint spring a model leaves out (about the reference pose), added to the declared one.

On a joint that declares a spring the added stiffness may be negative, down to the declared
one's (a total of 0): a spring declared too stiff or too soft is found as the difference (a
pendulum declaring 2 N m/rad where the plant has 2.6 was named a false force limit while the
hypothesis was withheld from joints with a spring of their own).
"""
from __future__ import annotations

from sim2real.physics.kinds.base import JOINT, Kind, add_magnitude, coef, set_coef


class Stiffness(Kind):
    owns = ("stiffness",)
    attach = JOINT
    declares = {"stiffness": (0.0, 0.0, 1e5, "N/m|Nm/rad", "joint spring added to the nominal one, about the reference pose")}
    order = 56
    effect = "joint_stiffness"

    def declared(self, m, index, kind, entry):
        k = float(m.jnt_stiffness[index])
        if k > 0:
            d, lo, hi, unit, doc = entry
            return d, -k, hi, unit, doc + f" (down to -{k:g}: the declared spring's own)"
        return entry

    def apply(self, pm, z, get, f) -> None:
        for i, p in pm.spec.of_kind("stiffness"):
            f["jnt_stiffness"] = get("jnt_stiffness").at[p.index].add(z[i])

    def export(self, ctx, p, v) -> None:
        if v != 0:
            j = ctx.spec.joint(ctx.system.joints[p.index])
            j.stiffness = set_coef(j.stiffness, coef(j.stiffness) + v)

    def candidates(self, system, sc, add, target) -> None:
        jn = system.joints[target]
        k0 = float(system.mj.jnt_stiffness[target])
        if k0 > 0:  # the declared spring off by a share of itself, either way
            add("joint_stiffness", jn, [f"stiffness:{jn}"], [(f * k0,) for f in (-0.3, -0.1, 0.1, 0.3)], [0.1 * k0],
                [(-0.95 * k0, 3.0 * k0)])
            return
        k = sc.force[target] / (0.5 * sc.range[target])
        add_magnitude(add, "joint_stiffness", jn, f"stiffness:{jn}", k, 3.0)
