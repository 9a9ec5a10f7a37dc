"""Position sensing: a constant offset and white noise on a joint's measured position (the
``sense`` hooks: where a measured state is made, and unmade)."""
from __future__ import annotations

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from sim2real.physics.kinds.base import JOINT, Kind, rows, take


class Sensor(Kind):
    owns = ("sensor_offset", "sensor_noise")
    attach = JOINT
    declares = {
        "sensor_offset": (0.0, -10.0, 10.0, "m|rad", "constant offset added to the measured joint position"),
        "sensor_noise": (0.0, 0.0, 1.0, "m|rad", "std of white noise added to the measured joint position"),
    }
    order = 57
    effect = "sensor_offset"

    def sense_setup(self, m, spec):
        joints = [p.index for _, p in spec.of_kind("sensor_offset")]
        if not joints:
            return None
        return {"qpos": np.array([m.jnt_qposadr[j] for j in joints], np.int32),
                "offset": rows(spec, "sensor_offset", joints), "noise": rows(spec, "sensor_noise", joints)}

    def sense(self, data, z, qpos, key):
        i, off, std = data["qpos"], take(z, data["offset"]), take(z, data["noise"])
        meas = qpos[i] + off + std * jax.random.normal(key, off.shape)
        return qpos.at[i].set(jnp.where((off != 0) | (std > 0), meas, qpos[i]))

    def measure(self, data, z, qpos):
        return qpos.at[data["qpos"]].add(take(z, data["offset"]))

    def unsense(self, data, z, qpos_meas):
        # a hypothesised offset changes where the joint really was
        return qpos_meas.at[data["qpos"]].add(-take(z, data["offset"]))

    def candidates(self, system, sc, add, target) -> None:
        jn = system.joints[target]
        R = sc.range[target]
        slide = system.mj.jnt_type[target] == mujoco.mjtJoint.mjJNT_SLIDE
        o = 0.05 * R if slide else min(0.05, 0.05 * R)
        add("sensor_offset", jn, [f"sensor_offset:{jn}"], [(s * f * o,) for f in (0.4, 2.0) for s in (-1, 1)],
            [o], [(-30 * o, 30 * o)])
