"""A fourth wave of models and logs a new user might bring (``probes.py`` and the second and third
waves have the others): a four-bar linkage closed by an ``<equality connect>``, a hobby arm logged
at 50 Hz, two minutes at 1 kHz, a declared joint spring stiffer in the plant. Recorded and
printed as the second wave's.
``PYTHONPATH=. python benchmarks/results/new_user_probes/fourth_wave.py [WORK] [PROBE ...]``.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import third_wave  # noqa: E402  (its runner, the same table)
from second_wave import PENDULUM  # noqa: E402

# crank (driven), coupler and rocker, the loop closed where the coupler's end meets the rocker's
FOURBAR = """<mujoco model="fourbar">
  <compiler angle="radian"/>
  <option timestep="0.001" integrator="implicitfast"/>
  <worldbody>
    <body name="crank">
      <joint name="crank" axis="0 1 0" damping="0.01"/>
      <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01" mass="0.1"/>
      <body name="coupler" pos="0.1 0 0">
        <joint name="coupler" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0.1" size="0.01" mass="0.2"/>
        <site name="coupler_end" pos="0.3 0 0.1"/>
      </body>
    </body>
    <body name="rocker" pos="0.3 0 0">
      <joint name="rocker" axis="0 1 0" {truth}/>
      <geom type="capsule" fromto="0 0 0 0.1 0 0.1" size="0.01" mass="0.15"/>
      <site name="rocker_end" pos="0.1 0 0.1"/>
    </body>
  </worldbody>
  <equality><connect site1="coupler_end" site2="rocker_end"/></equality>
  <actuator><motor name="m" joint="crank" ctrlrange="-0.3 0.3"/></actuator>
</mujoco>"""

SPRING = """<mujoco model="spring_pendulum">
  <option timestep="0.001"/>
  <worldbody>
    <body name="rod" pos="0 0 1">
      <joint name="hinge" axis="0 1 0" damping="0.01" springref="0" {truth}/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/>
    </body>
  </worldbody>
  <actuator><motor name="m" joint="hinge" ctrlrange="-2 2"/></actuator>
</mujoco>"""

# name: (model text, the truth for {truth}, words, drive, extras, training recordings)
PROBES = {
    "fourbar_rocker_friction": (FOURBAR, 'frictionloss="0.02"', "coulomb_friction@rocker 0.02 N m (a closed loop)",
                                "multisine", {}, 2),
    "pendulum_logged_50hz_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m (50 Hz log)",
                                      "multisine", {"period": 0.02}, 2),
    "pendulum_two_minutes_1khz_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m "
                                           "(3 x 120 s at 1 kHz)", "multisine", {"period": 0.001, "seconds": 120.0}, 2),
    # (the model's stiffness="2", the plant's "2" followed by the truth's ".6")
    "declared_spring_stiffer": (SPRING.replace("{truth}", 'stiffness="2{truth}"'), ".6",
                                "the declared stiffness 2 N m/rad is 2.6 (a parameter, no missing effect)",
                                "multisine", {}, 2),
}


def main(work, only=()):
    third_wave.main(work, only, PROBES)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_4", tuple(sys.argv[2:]))
