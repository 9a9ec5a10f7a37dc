"""Position sensing: a constant offset and white noise on a joint's measured position (applied by
``Effects.sense`` / ``measure`` / ``unsense``, where the measured state is made)."""
from __future__ import annotations

import mujoco

from sim2real.physics.kinds.base import JOINT, Kind


class Sensor(Kind):
    owns = ("sensor_offset", "sensor_noise")
    attach = JOINT
    declares = {
        "sensor_offset": (0.0, -10.0, 10.0, "m|rad", "constant offset added to the measured joint position"),
        "sensor_noise": (0.0, 0.0, 1.0, "m|rad", "std of white noise added to the measured joint position"),
    }
    order = 57
    effect = "sensor_offset"

    def candidates(self, system, sc, add, target) -> None:
        jn = system.joints[target]
        R = sc.range[target]
        slide = system.mj.jnt_type[target] == mujoco.mjtJoint.mjJNT_SLIDE
        o = 0.05 * R if slide else min(0.05, 0.05 * R)
        add("sensor_offset", jn, [f"sensor_offset:{jn}"], [(s * f * o,) for f in (0.4, 2.0) for s in (-1, 1)],
            [o], [(-30 * o, 30 * o)])
