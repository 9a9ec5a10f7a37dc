"""A constant force or torque on a joint that the model leaves out: a torque sensor's or current
amplifier's bias, a gravity compensation that does not match the arm, a cable or hose pulling
one way.

Simulated as a known generalised force held over the control step (``qfrc_applied``: the
``force`` hook, ``effects.constant_force``), signed, neutral at 0. Written into MJCF as an actuator
whose force is its bias alone (gain 0, so its ``ctrl`` does nothing), appended after the model's
own actuators so their ``ctrl`` indices do not change, as the Coulomb asymmetry's offset is.
Offered to the diagnosis as ``torque_offset`` when asked for (``effects=[..., torque_offset]``):
the default search's thresholds were tuned without it.
"""
from __future__ import annotations

import mujoco
import numpy as np

from sim2real.physics.kinds.base import JOINT, Kind, add_constant_force, rows, take

_ONE_DOF = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))


class TorqueOffset(Kind):
    owns = ("torque_offset",)
    attach = JOINT
    declares = {"torque_offset": (0.0, -1e4, 1e4, "N|Nm", "constant generalised force on the joint (signed)")}
    order = 59
    effect = "torque_offset"
    default_candidate = False

    def force_setup(self, m, spec):
        joints = [p.index for _, p in spec.of_kind("torque_offset") if int(m.jnt_type[p.index]) in _ONE_DOF]
        if not joints:
            return None
        return np.array([m.jnt_dofadr[j] for j in joints], np.int32), rows(spec, "torque_offset", joints)

    def force(self, data, z):
        return take(z, data)

    def export(self, ctx, p, v) -> None:
        if v == 0:
            return
        jn = ctx.system.joints[p.index]
        add_constant_force(ctx, p.name, f"sim2real_torque_offset:{jn}", jn, v)

    def candidates(self, system, sc, add, target) -> None:
        m = system.mj
        if int(m.jnt_type[target]) not in _ONE_DOF:
            return
        jn = system.joints[target]
        f = sc.force[target]  # the RMS force the joint needs along the data
        add("torque_offset", jn, [f"torque_offset:{jn}"], [(s * k * f,) for k in (0.1, 0.3) for s in (-1, 1)],
            [0.1 * f], [(-3.0 * f, 3.0 * f)])
