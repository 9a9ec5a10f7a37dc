"""An eighth wave: what robot arms and drives in a lab have, each written here on native MuJoCo:

- a compliant transmission (a harmonic drive's flexspline, a series-elastic actuator): the motor
  turns a rotor of its own (armature 0.004 kg m^2) that drives the pendulum through a torsion spring
  of 20 N m/rad (a damper of 0.02 N m s/rad beside it), no dead band; the model has the motor on
  the pendulum's joint. The library's nearest name is a ``backlash`` whose band is (near) zero wide:
  a motor-side inertia behind a compliant mesh.
- the same Coulomb friction, 0.1 N m, on all three joints of a vertical 3-link arm (motors of
  3, 1.2 and 0.4 N m: about half of what gravity asks of each with the arm held out level, so it
  swings, never over the top);
- a cart-pole pushed through a 15 ms delay with a 1.5 N Coulomb friction on its rail (two effects);
- a slider whose rail has a Coulomb friction of 0.8 N and 1.5 N s/m of damping where the model
  declares 1 (an effect and a parameter at once).

Recorded and printed as the second wave's (3 recordings of 8 s at 200 Hz, position noise 1e-3, 2 to
train on, the third held out).
``PYTHONPATH=. python benchmarks/results/new_user_probes/eighth_wave.py [WORK] [PROBE ...]``.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import third_wave  # noqa: E402  (its runner, the same table)
from second_wave import PENDULUM, SLIDER  # noqa: E402
from third_wave import CARTPOLE  # noqa: E402

# the plant of the compliant transmission: the motor on a rotor joint of its own, coaxial with the
# pendulum's (the two bodies do not touch: the rotor's geom collides with nothing)
ELASTIC_PLANT = """<mujoco model="pendulum">
  <option timestep="0.001"/>
  <worldbody>
    <body name="rotor" pos="0 0 1">
      <joint name="motor_side" axis="0 1 0" armature="0.004"/>
      <geom type="cylinder" size="0.01 0.01" mass="0.001" contype="0" conaffinity="0"/>
    </body>
    <body name="rod" pos="0 0 1">
      <joint name="hinge" axis="0 1 0" damping="0.01"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/>
    </body>
  </worldbody>
  <actuator><motor name="m" joint="motor_side" ctrlrange="-2 2"/></actuator>
</mujoco>"""


def torsion_spring(qpos, qvel, k=20.0, c=0.02):
    """The transmission's torque (N m) on (rotor, pendulum): a spring ``k`` (N m/rad) and damper
    ``c`` (N m s/rad) between the two angles."""
    tau = k * (qpos[0] - qpos[1]) + c * (qvel[0] - qvel[1])
    return np.array([-tau, tau])


ARM3 = """<mujoco model="arm3">
  <option timestep="0.001" integrator="implicitfast"/>
  <worldbody>
    <body name="l1" pos="0 0 1">
      <joint name="j1" axis="0 1 0" damping="0.05" {truth}/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      <body name="l2" pos="0.3 0 0">
        <joint name="j2" axis="0 1 0" damping="0.03" {truth}/>
        <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.025" mass="0.6"/>
        <body name="l3" pos="0.25 0 0">
          <joint name="j3" axis="0 1 0" damping="0.02" {truth}/>
          <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.3"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="a1" joint="j1" ctrlrange="-3 3"/>
    <motor name="a2" joint="j2" ctrlrange="-1.2 1.2"/>
    <motor name="a3" joint="j3" ctrlrange="-0.4 0.4"/>
  </actuator>
</mujoco>"""

# the cart-pole with the truth on the rail (the third wave's puts it on the pole's hinge)
CART_RAIL = CARTPOLE.replace('<joint name="hinge" axis="0 1 0" {truth}/>', '<joint name="hinge" axis="0 1 0"/>').replace(
    'damping="2" range="-1 1"/>', 'damping="2" range="-1 1" {truth}/>')

# the slider's plant: its rail's damping 1.5 where the model declares 1, and a friction the model leaves out
SLIDER_PLANT = SLIDER.format(truth='frictionloss="0.8"').replace('damping="1"', 'damping="1.5"')

# name: (model text, the truth for {truth}, words, drive, extras, training recordings)
PROBES = {
    "pendulum_elastic_transmission": (PENDULUM, "", "a compliant transmission: 20 N m/rad spring to a 0.004 kg m^2 "
                                      "rotor, no band (nearest name: backlash@m, width ~0)", "multisine",
                                      {"plant": ELASTIC_PLANT, "qfrc": torsion_spring}, 2),
    "arm3_friction_every_joint": (ARM3, 'frictionloss="0.1"', "coulomb_friction 0.1 N m on j1, j2 and j3",
                                  "multisine", {}, 2),
    "cartpole_delay_and_rail_friction": (CART_RAIL, 'frictionloss="1.5"', "action_delay 0.015 s + "
                                         "coulomb_friction@slider 1.5 N", "steps", {"delay_s": 0.015}, 2),
    "slider_friction_and_more_damping": (SLIDER, "", "coulomb_friction@rail 0.8 N (and damping 1 -> 1.5 N s/m, "
                                         "a parameter)", "steps", {"plant": SLIDER_PLANT}, 2),
}


if __name__ == "__main__":
    third_wave.main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_8", tuple(sys.argv[2:]), PROBES)
