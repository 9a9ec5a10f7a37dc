"""A ninth wave: the size of arm a lab has, and a logger that loses samples, on native MuJoCo:

- a 6-joint arm (base yaw, shoulder, elbow, two wrist pitches and a wrist roll; 8.8 kg; masses from
  geoms; a declared damping and armature on every joint as a datasheet gives them) on `position`
  servos with `dampratio`, stepped at 2 ms, logged at 250 Hz, setpoints a multisine within +-0.8 rad
  of the upright pose: a Coulomb friction of 1.5 N m on the elbow, and the same arm with nothing
  hidden (parameter-only: the forearm 20% heavier than the model says);
- a pendulum whose logger lost 30 samples (150 ms) in the middle of every recording.

Recorded and printed as the second wave's (3 recordings of 8 s, position noise 1e-3, 2 to train
on, the third held out).
``PYTHONPATH=. python benchmarks/results/new_user_probes/ninth_wave.py [WORK] [PROBE ...]``.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import third_wave  # noqa: E402  (its runner, the same table)
from second_wave import PENDULUM  # noqa: E402

ARM6 = """<mujoco model="arm6">
  <option timestep="0.002" integrator="implicitfast"/>
  <default>
    <joint damping="0.4" armature="0.02"/>
    <position dampratio="1" ctrlrange="-0.8 0.8"/>
  </default>
  <worldbody>
    <body name="turret" pos="0 0 0.1">
      <joint name="base" axis="0 0 1"/>
      <geom type="cylinder" size="0.07 0.05" mass="2.5"/>
      <body name="upper" pos="0 0 0.08">
        <joint name="shoulder" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.4" size="0.045" mass="3"/>
        <body name="fore" pos="0 0 0.4">
          <joint name="elbow" axis="0 1 0" {truth}/>
          <geom type="capsule" fromto="0 0 0 0.35 0 0" size="0.035" mass="1.8"/>
          <body name="wrist_a" pos="0.35 0 0">
            <joint name="wrist1" axis="0 1 0"/>
            <geom type="capsule" fromto="0 0 0 0.08 0 0" size="0.03" mass="0.6"/>
            <body name="wrist_b" pos="0.08 0 0">
              <joint name="wrist2" axis="1 0 0"/>
              <geom type="cylinder" fromto="0 0 0 0.06 0 0" size="0.03" mass="0.4"/>
              <body name="flange" pos="0.06 0 0">
                <joint name="wrist3" axis="0 1 0"/>
                <geom type="box" pos="0.03 0 0" size="0.03 0.04 0.02" mass="0.5"/>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="p_base" joint="base" kp="150"/>
    <position name="p_shoulder" joint="shoulder" kp="300"/>
    <position name="p_elbow" joint="elbow" kp="150"/>
    <position name="p_wrist1" joint="wrist1" kp="30"/>
    <position name="p_wrist2" joint="wrist2" kp="15"/>
    <position name="p_wrist3" joint="wrist3" kp="10"/>
  </actuator>
</mujoco>"""

# the parameter-only arm's plant: the forearm 20% heavier than the model says
ARM6_HEAVY_FORE = ARM6.format(truth="").replace('size="0.035" mass="1.8"', 'size="0.035" mass="2.16"')

# name: (model text, the truth for {truth}, words, drive, extras, training recordings)
PROBES = {
    "arm6_position_elbow_friction": (ARM6, 'frictionloss="1.5"', "coulomb_friction@elbow 1.5 N m (6 joints, "
                                     "position servos)", "multisine", {"period": 0.004}, 2),
    "arm6_position_heavier_forearm": (ARM6, "", "the forearm 2.16 kg where the model says 1.8 (a parameter, no "
                                      "missing effect)", "multisine", {"period": 0.004, "plant": ARM6_HEAVY_FORE}, 2),
    "pendulum_lost_samples_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m (30 "
                                       "samples lost mid-recording)", "multisine", {"drop": (800, 30)}, 2),
}


if __name__ == "__main__":
    third_wave.main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_9", tuple(sys.argv[2:]), PROBES)
