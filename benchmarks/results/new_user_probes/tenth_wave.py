"""A tenth wave: thrust where the force comes from a propeller, written as MuJoCo writes thrusters
(a `motor` on a `site`, its gear the thrust's direction in the site's frame), on native MuJoCo:

- an aero pendulum (a rod on a hinge with a propeller at its tip, thrust 0-0.6 N across the rod, the
  classic control-lab rig): a motor lag of 40 ms on the propeller (written here, at the plant's
  step), a Coulomb friction of 0.02 N m on the hinge, a thrust limit of 0.4 N (the plant's
  `forcerange`, the model's none);
- a cart on a rail pushed by a thruster (+-5 N; a hovercraft or an air-bearing stage, under force
  control, so it drifts): a command delay of 20 ms;
- a quadrotor (a free body, four propellers on sites, each thrust with its drag torque about the
  body's z axis) flying to setpoints that jump every 0.4 s under a cascaded PD controller computed at 200 Hz on the
  noisy measured pose (1e-3 m and rad) and a gyro's rates (1e-2 rad/s), the thrusts sent
  recorded, the pose logged without velocities: a motor lag of 30 ms on all four motors, a 0.12 kg
  camera under and ahead of the centre (its mass and place unknown to the model), and a drone 10%
  heavier than the model says (parameter-only).

Recorded and printed as the second wave's (3 recordings of 8 s at 200 Hz from a 1 ms step, position
noise 1e-3, 2 to train on, the third held out).
``PYTHONPATH=. python benchmarks/results/new_user_probes/tenth_wave.py [WORK] [PROBE ...]``.
"""
import os
import sys

import mujoco
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import third_wave  # noqa: E402  (its runner, the same table)

AERO = """<mujoco model="aero_pendulum">
  <option timestep="0.001" integrator="implicitfast"/>
  <worldbody>
    <body name="rod" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.002" {truth}/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.008" mass="0.06"/>
      <geom name="motor" type="cylinder" pos="0 0 -0.3" size="0.015 0.015" mass="0.05"/>
      <site name="prop" pos="0 0 -0.3"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="thrust" site="prop" gear="1 0 0 0 0 0" ctrlrange="0 0.6"/>
  </actuator>
</mujoco>"""

CART = """<mujoco model="thruster_cart">
  <option timestep="0.001" integrator="implicitfast"/>
  <worldbody>
    <body name="cart" pos="0 0 0.1">
      <joint name="rail" type="slide" axis="1 0 0" damping="0.8" {truth}/>
      <geom type="box" size="0.15 0.1 0.05" mass="1.2"/>
      <site name="fan" pos="-0.15 0 0.05"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="fan" site="fan" gear="1 0 0 0 0 0" ctrlrange="-5 5"/>
  </actuator>
</mujoco>"""

# name: (model text, the truth for {truth}, words, drive, extras, training recordings)
PROBES = {
    "aero_pendulum_motor_lag": (AERO, "", "motor_lag 0.04 s on the propeller (written here)", "multisine",
                                {"lag_s": 0.04}, 2),
    "aero_pendulum_friction": (AERO, 'frictionloss="0.02"', "coulomb_friction@hinge 0.02 N m", "multisine", {}, 2),
    "aero_pendulum_thrust_limit": (AERO, "", "actuator_saturation@thrust 0.4 N (the plant's forcerange)", "multisine",
                                   {"plant": AERO.format(truth="").replace('ctrlrange="0 0.6"',
                                                                           'ctrlrange="0 0.6" forcerange="-0.4 0.4"')},
                                   2),
    "thruster_cart_delay": (CART, "", "action_delay 0.02 s (written here)", "multisine", {"delay_s": 0.02}, 2),
}

QUAD = """<mujoco model="quadrotor">
  <option timestep="0.001" integrator="implicitfast"/>
  <worldbody>
    <body name="quad" pos="0 0 1">
      <freejoint name="root"/>
      <geom name="core" type="box" size="0.06 0.06 0.02" mass="{core}"/>
      <geom type="capsule" fromto="-0.12 -0.12 0 0.12 0.12 0" size="0.01" mass="0.1"/>
      <geom type="capsule" fromto="-0.12 0.12 0 0.12 -0.12 0" size="0.01" mass="0.1"/>
      <site name="r1" pos="0.12 0.12 0.01"/><site name="r2" pos="-0.12 0.12 0.01"/>
      <site name="r3" pos="-0.12 -0.12 0.01"/><site name="r4" pos="0.12 -0.12 0.01"/>
      {truth}
    </body>
  </worldbody>
  <actuator>
    <motor name="m1" site="r1" gear="0 0 1 0 0 0.02" ctrlrange="0 5"/>
    <motor name="m2" site="r2" gear="0 0 1 0 0 -0.02" ctrlrange="0 5"/>
    <motor name="m3" site="r3" gear="0 0 1 0 0 0.02" ctrlrange="0 5"/>
    <motor name="m4" site="r4" gear="0 0 1 0 0 -0.02" ctrlrange="0 5"/>
  </actuator>
</mujoco>"""
QUAD_PROBES = {
    "quadrotor_motor_lag": ("", 0.6, "motor_lag 0.03 s on all four motors (written here)", {"lag_s": 0.03}),
    "quadrotor_camera_payload": ('<geom type="box" pos="0.04 0 -0.05" size="0.02 0.02 0.02" mass="0.12"/>', 0.6,
                                 "mass_offset@quad: a 0.12 kg camera 4 cm ahead, 5 cm under the centre", {}),
    "quadrotor_heavier": ("", 0.68, "the drone 10% heavier (0.88 kg for 0.8; parameter-only)", {}),
}


def _euler(q):
    """Roll, pitch, yaw (rad) of the unit quaternion ``q`` (w, x, y, z)."""
    w, x, y, z = q / np.linalg.norm(q)
    return (np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)), np.arcsin(np.clip(2 * (w * y - z * x), -1, 1)),
            np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))


def record_quad(name, truth, core, extras, work):
    """Three 8 s flights of the plant (the model with ``truth`` in the body and its core ``core`` kg)
    under a cascaded PD controller on the noisy measurements; returns the nominal model's path and
    the recordings'."""
    nominal = os.path.join(work, f"{name}.xml")
    open(nominal, "w").write(QUAD.format(truth="", core=0.6))
    m = mujoco.MjModel.from_xml_string(QUAD.format(truth=truth, core=core))
    sub, period, mass, g = 5, 0.005, 0.8, 9.81    # the controller's mass: the model's
    xy = np.array([[0.12, 0.12], [-0.12, 0.12], [-0.12, -0.12], [0.12, -0.12]])
    mix = np.linalg.inv(np.stack([np.ones(4), xy[:, 1], -xy[:, 0], 0.02 * np.array([1, -1, 1, -1])]))
    inertia = np.array([0.0018, 0.0018, 0.0032])   # (a rough guess, as a lab's controller has)
    rng = np.random.default_rng(3)
    paths = []
    for r in range(3):
        d = mujoco.MjData(m)
        mujoco.mj_forward(m, d)
        steps = rng.uniform(-1, 1, (40, 4)) * np.array([0.4, 0.4, 0.25, 0.5])   # setpoints held 0.4 s
        u_eff, rows, v_est, p_prev = np.full(4, mass * g / 4), [], np.zeros(3), None
        for k in range(int(8.0 / period)):
            t = k * period
            ref = steps[int(t / 0.4)] + np.array([0, 0, 1.0, 0])
            pose = d.qpos + rng.normal(0, 1e-3, 7)
            gyro = d.qvel[3:] + rng.normal(0, 1e-2, 3)
            p = pose[:3]
            if p_prev is not None:   # velocity: the positions differenced, filtered over ~30 ms
                v_est += ((p - p_prev) / period - v_est) * 0.15
            p_prev = p
            roll, pitch, yaw = _euler(pose[3:])
            a = 4.0 * (ref[:3] - p) - 3.0 * v_est
            c, s_ = np.cos(yaw), np.sin(yaw)
            pitch_d = np.clip((c * a[0] + s_ * a[1]) / g, -0.4, 0.4)
            roll_d = np.clip(-(-s_ * a[0] + c * a[1]) / g, -0.4, 0.4)
            yaw_err = np.arctan2(np.sin(ref[3] - yaw), np.cos(ref[3] - yaw))
            torque = inertia * (100 * np.array([roll_d - roll, pitch_d - pitch, yaw_err]) - 14 * gyro)
            thrust = mass * (g + a[2]) / max(np.cos(roll) * np.cos(pitch), 0.5)
            cmd = np.clip(mix @ np.concatenate([[thrust], torque]), 0, 5)
            rows.append([t + 0.25, *pose, *cmd])
            for _ in range(sub):
                u_eff = u_eff + (cmd - u_eff) * (1 - np.exp(-m.opt.timestep / extras.get("lag_s", 1e-12)))
                d.ctrl[:] = u_eff
                mujoco.mj_step(m, d)
        paths.append(os.path.join(work, f"{name}_{r}.csv"))
        cols = [f"qpos:root:{c}" for c in ("x", "y", "z", "qw", "qx", "qy", "qz")] + [f"ctrl:m{i}" for i in range(1, 5)]
        np.savetxt(paths[-1], np.array(rows), delimiter=",", header="time," + ",".join(cols), comments="")
    return nominal, paths


def main(work, only=()):
    from probes import diagnose_and_print

    third_wave.main(work, only, {k: v for k, v in PROBES.items() if not only or k in only})
    for name, (truth, core, words, extras) in QUAD_PROBES.items():
        if not only or name in only:
            nominal, paths = record_quad(name, truth, core, extras, work)
            diagnose_and_print(name, words, nominal, paths, work, 2)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_10", tuple(sys.argv[2:]))
