"""A third wave of models a new user might bring (``probes.py``, ``second_wave.py`` have the
others): a leg on a test rig under position servos, an under-actuated cart-pole, one long
recording and nothing held out, a pusher sliding a box on the floor (contacts), a motor lag
written here. Recorded and printed as the second wave's.
``PYTHONPATH=. python benchmarks/results/new_user_probes/third_wave.py [WORK] [PROBE ...]``.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probes import diagnose_and_print  # noqa: E402
from second_wave import PENDULUM, record  # noqa: E402

# a leg hanging from a test rig: hip, knee and ankle on position servos (ranges in radians, so the
# compiler says so: its first version did not, see the README); the truth adds a 0.3 kg
# sensor at the shank's middle
LEG = """<mujoco model="leg_rig">
  <compiler angle="radian"/>
  <option timestep="0.001" integrator="implicitfast"/>
  <default><joint damping="0.05" armature="0.005"/><position kp="60" kv="2"/></default>
  <worldbody>
    <body name="thigh" pos="0 0 1">
      <joint name="hip" axis="0 1 0" range="-1.5 1.5"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.25" size="0.04" mass="1.2"/>
      <body name="shank" pos="0 0 -0.25">
        <joint name="knee" axis="0 1 0" range="-2.5 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.25" size="0.03" mass="0.6"/>
        {truth}
        <body name="foot" pos="0 0 -0.25">
          <joint name="ankle" axis="0 1 0" range="-0.8 0.8"/>
          <geom type="box" size="0.08 0.03 0.015" pos="0.03 0 -0.015" mass="0.2"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="hip" joint="hip" ctrlrange="-1 1"/>
    <position name="knee" joint="knee" ctrlrange="-2 -0.2"/>
    <position name="ankle" joint="ankle" kp="10" kv="0.3" ctrlrange="-0.5 0.5"/>
  </actuator>
</mujoco>"""

CARTPOLE = """<mujoco model="cartpole">
  <option timestep="0.002"/>
  <worldbody>
    <body name="cart">
      <joint name="slider" type="slide" axis="1 0 0" damping="2" range="-1 1"/>
      <geom type="box" size="0.1 0.05 0.05" mass="1"/>
      <body name="pole">
        <joint name="hinge" axis="0 1 0" {truth}/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.02" mass="0.2"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor name="push" joint="slider" ctrlrange="-8 8"/></actuator>
</mujoco>"""

# a pusher on a position servo, a box on a rail resting on the floor (free to lift, so its weight
# presses on the floor: on the rail alone the joint carried it and nothing rubbed, the first
# version's mistake): the pusher's pad shoves the box, which rubs on the floor (MuJoCo's contact
# friction, the truth's lower: on the floor and the box both, since a contact takes the larger of
# its two geoms' frictions -- the second version lowered the box's alone, which changed nothing)
PUSHER = """<mujoco model="pusher">
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1" {truth}/>
    <body name="pusher" pos="0 0 0.05">
      <joint name="ram" type="slide" axis="1 0 0" range="-0.2 0.6" damping="20"/>
      <geom type="box" size="0.02 0.05 0.03" mass="0.5" contype="2" conaffinity="2"/>
    </body>
    <body name="box" pos="0.1 0 0.05">
      <joint name="rail" type="slide" axis="1 0 0"/>
      <joint name="lift" type="slide" axis="0 0 1"/>
      <geom name="box" type="box" size="0.05 0.05 0.05" mass="1" contype="3" conaffinity="3" {truth}/>
    </body>
  </worldbody>
  <actuator><position name="ram" joint="ram" kp="300" kv="30" ctrlrange="-0.2 0.6"/></actuator>
</mujoco>"""

ARM = """<mujoco model="arm2">
  <option timestep="0.001" integrator="implicitfast"/>
  <worldbody>
    <body name="l1" pos="0 0 0.5">
      <joint name="j1" axis="0 0 1" damping="0.05"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      <body name="l2" pos="0.3 0 0">
        <joint name="j2" axis="0 0 1" damping="0.02"/>
        <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.025" mass="0.5"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor name="a1" joint="j1" ctrlrange="-1.5 1.5"/><motor name="a2" joint="j2" ctrlrange="-0.6 0.6"/></actuator>
</mujoco>"""

# name: (model text, the truth for {truth}, words, drive, extras, training recordings (the rest held out))
PROBES = {
    "leg_rig_position_payload": (LEG, '<geom type="sphere" pos="0 0 -0.12" size="0.02" mass="0.3"/>',
                                 "mass_offset@shank 0.3 kg at 0.12 m", "steps", {}, 2),
    "cartpole_pole_damping": (CARTPOLE, 'damping="0.01"', "viscous_damping@hinge 0.01 N m s/rad (unactuated)",
                              "multisine", {}, 2),
    "one_long_recording_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m (one 20 s "
                                    "recording, nothing held out)", "multisine", {"count": 1, "seconds": 20.0}, 1),
    "pusher_box_floor_friction": (PUSHER, 'friction="0.3 0.005 0.0001"',
                                  "the box-floor friction 0.3 (model: MuJoCo's default 1)",
                                  "steps", {}, 2),
    "arm_motor_lag": (ARM, "", "motor_lag 0.03 s on both motors (written here)", "multisine", {"lag_s": 0.03}, 2),
}


def main(work, only=(), probes=None):
    """Record and diagnose ``probes`` (this wave's by default; the fourth wave passes its own)."""
    os.makedirs(work, exist_ok=True)
    print("| probe | truth | named | values | held-out NRMSE before -> after | seconds |")
    print("|---|---|---|---|---|---|")
    for name, (text, truth, words, drive, extras, train) in (PROBES if probes is None else probes).items():
        if only and name not in only:
            continue
        nominal, paths = record(name, text, truth, drive, extras, work)
        diagnose_and_print(name, words, nominal, paths, work, train)
        asked = {"arm_motor_lag": "motor_lag_all", "pusher_box_floor_friction": "contact_friction"}
        if name in asked:  # the same recordings, with a hypothesis searched only when asked for
            from sim2real.sysid.diagnose import EFFECTS
            diagnose_and_print(name + "_asked", words, nominal, paths, work, train,
                               effects=tuple(EFFECTS) + (asked[name],))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_3", tuple(sys.argv[2:]))
