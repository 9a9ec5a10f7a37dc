"""Backlash: a dead band between an actuator and its joint, crossed by the motor side's inertia
(``Effects.actuate`` runs it in the command path)."""
from __future__ import annotations

import mujoco
import numpy as np

from sim2real.physics.kinds.base import ACTUATOR, Kind, name_of
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
