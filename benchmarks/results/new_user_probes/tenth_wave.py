"""A tenth wave: thrust where the force comes from a propeller, written as MuJoCo writes thrusters
(a `motor` on a `site`, its gear the thrust's direction in the site's frame), on native MuJoCo:

- an aero pendulum (a rod on a hinge with a propeller at its tip, thrust 0-0.6 N across the rod, the
  classic control-lab rig): a motor lag of 40 ms on the propeller (written here, at the plant's
  step), a Coulomb friction of 0.02 N m on the hinge, a thrust limit of 0.4 N (the plant's
  `forcerange`, the model's none);
- a cart on a rail pushed by a thruster (+-5 N; a hovercraft or an air-bearing stage, under force
  control, so it drifts): a command delay of 20 ms.

Recorded and printed as the second wave's (3 recordings of 8 s at 200 Hz from a 1 ms step, position
noise 1e-3, 2 to train on, the third held out).
``PYTHONPATH=. python benchmarks/results/new_user_probes/tenth_wave.py [WORK] [PROBE ...]``.
"""
import os
import sys

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


if __name__ == "__main__":
    third_wave.main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_10", tuple(sys.argv[2:]), PROBES)
