"""A fifth wave of models and logs a new user might bring (the first four in ``probes.py`` and
``second_wave.py`` .. ``fourth_wave.py``): a `position` servo written with MuJoCo's `dampratio`,
a pendulum excited by one sine (the first test a lab runs), and an arm whose motors deliver 80% of
the model's torque (a motor constant off: a parameter, no missing effect). Recorded and printed as
the second wave's. ``PYTHONPATH=. python benchmarks/results/new_user_probes/fifth_wave.py [WORK] [PROBE ...]``.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import third_wave  # noqa: E402  (its runner, the same table)
from second_wave import PENDULUM  # noqa: E402

# a pendulum on a position servo whose damping is given as a damping ratio (MuJoCo >= 3.1)
DAMPRATIO = """<mujoco model="dampratio_servo">
  <option timestep="0.001" integrator="implicitfast"/>
  <worldbody>
    <body name="rod" pos="0 0 1">
      <joint name="hinge" axis="0 1 0" damping="0.01" {truth}/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/>
    </body>
  </worldbody>
  <actuator><position name="servo" joint="hinge" kp="4" dampratio="0.7" ctrlrange="-1.2 1.2"/></actuator>
</mujoco>"""

# a horizontal 2-link arm on two motors; the truth's gears are 0.8 (a motor constant, a gear
# ratio or an amplifier gain 20% below the datasheet's)
ARM = third_wave.ARM.replace('<motor name="a1" joint="j1"', '<motor name="a1" joint="j1" {truth}').replace(
    '<motor name="a2" joint="j2"', '<motor name="a2" joint="j2" {truth}')

# name: (model text, the truth for {truth}, words, drive, extras, training recordings)
PROBES = {
    "position_dampratio_friction": (DAMPRATIO, 'frictionloss="0.03"', "coulomb_friction@hinge 0.03 N m "
                                    "(a position servo with dampratio)", "steps", {}, 2),
    "pendulum_one_sine_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m "
                                   "(one 0.7 Hz sine)", "sine", {}, 2),
    "arm_motors_weaker": (ARM, 'gear="0.8"', "both motors' gear 0.8 (a parameter, no missing effect)",
                          "multisine", {}, 2),
}


def main(work, only=()):
    third_wave.main(work, only, PROBES)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_5", tuple(sys.argv[2:]))
