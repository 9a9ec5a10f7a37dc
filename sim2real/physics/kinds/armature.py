"""Rotor inertia a model leaves out: a geared motor's rotor, reflected through its gear (N^2 times
the rotor's inertia), adds to the joint's inertia without adding weight -- MuJoCo's ``armature``.

A diagnosis parameter (``armature:<joint>``, added to the joint's declared armature; on a joint
that declares one, either sign down to a total of 0), not an env's: ``params`` builds it for the
diagnosis' ``System``. Searched as ``rotor_inertia`` when asked for, or in place of a named band
(``SelectConfig.rotor``). Left out, a pendulum whose plant had a 0.01 kg m^2 rotor was named a
backlash: the band's motor-side inertia (0.0064) stood in for the rotor; fitted in the band's
place, the rotor predicts 200x better and replaces it (``SelectConfig.rotor_ratio``;
``benchmarks/results/new_user_probes/README.md``, sixth wave).
"""
from __future__ import annotations

import mujoco

from sim2real.physics.kinds.base import JOINT, Kind, joint_dofs, name_of
from sim2real.physics.params import Param


def params(m: mujoco.MjModel, joints) -> list[Param]:
    """``armature:<joint>`` for each hinge or slide of ``joints``: neutral at 0, down to minus the
    joint's declared armature, up to 1e3 (kg m^2 for a hinge, kg for a slide)."""
    ps = []
    for j in joints:
        a0 = float(m.dof_armature[m.jnt_dofadr[j]])
        slide = int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_SLIDE)
        ps.append(Param(f"armature:{name_of(m, mujoco.mjtObj.mjOBJ_JOINT, j)}", 0.0, -a0, 1e3,
                        "kg" if slide else "kg m^2", "rotor inertia added to the joint's armature (reflected "
                        "through its gear)", "armature", j))
    return ps


class RotorInertia(Kind):
    owns = ("armature",)
    attach = JOINT
    order = 59.5
    effect = "rotor_inertia"
    # asked for (``effects=[..., rotor_inertia]``): the default search's thresholds were tuned without it
    default_candidate = False

    def apply(self, pm, z, get, f) -> None:
        for i, p in pm.spec.of_kind("armature"):
            f["dof_armature"] = get("dof_armature").at[joint_dofs(pm.mj, p.index)].add(z[i])

    def export(self, ctx, p, v) -> None:
        if v != 0:
            j = ctx.spec.joint(ctx.system.joints[p.index])
            j.armature = float(j.armature) + float(v)

    def candidates(self, system, sc, add, target) -> None:
        jn = system.joints[target]
        name = f"armature:{jn}"
        if name not in system.spec or sc.inertia is None:
            return
        inertia = float(sc.inertia[target])  # the joint's inertia at the data's mean pose
        lo = float(system.spec[name].low)
        add("rotor_inertia", jn, [name], [(f * inertia,) for f in (0.03, 0.1, 0.3)], [0.1 * inertia],
            [(lo, 10.0 * inertia)])
