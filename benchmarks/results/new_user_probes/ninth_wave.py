"""A ninth wave: the size of arm a lab has, and a logger that loses samples, on native MuJoCo:

- a 6-joint arm (base yaw, shoulder, elbow, two wrist pitches and a wrist roll; 8.8 kg; masses from
  geoms; a declared damping and armature on every joint as a datasheet gives them) on `position`
  servos with `dampratio`, stepped at 2 ms, logged at 250 Hz, setpoints a multisine within +-0.8 rad
  of the upright pose: a Coulomb friction of 1.5 N m on the elbow, and the same arm with nothing
  hidden (parameter-only: the forearm 20% heavier than the model says); and the friction on the
  same arm written as menagerie writes arms (links as OBJ meshes beside the model, a collision mesh
  and a visual one per link);
- a leg on a test rig (its base on a vertical rail, hip and knee on position servos, the foot on
  the floor: contacts that happen): a Coulomb friction of 3 N on the rail, and a 15 ms command delay;
- a pendulum whose logger lost 30 samples (150 ms) in the middle of every recording.

Recorded and printed as the second wave's (3 recordings of 8 s, position noise 1e-3, 2 to train
on, the third held out).
``PYTHONPATH=. python benchmarks/results/new_user_probes/ninth_wave.py [WORK] [PROBE ...]``.
"""
import os
import re
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



def box_obj(lo, hi):
    """A box from corner ``lo`` to corner ``hi`` (m) as OBJ text: 8 vertices, 12 triangles."""
    v = [(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
    return "".join(f"v {x} {y} {z}\n" for x, y, z in v) + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)


# the same arm as menagerie's arms are written: links as meshes (OBJ files beside the model), a
# collision mesh per link and a visual one that collides with nothing and weighs nothing
MESHES = {"turret.obj": box_obj((-0.07, -0.07, -0.05), (0.07, 0.07, 0.05)),
          "upper.obj": box_obj((-0.045, -0.045, 0.0), (0.045, 0.045, 0.4)),
          "fore.obj": box_obj((0.0, -0.035, -0.035), (0.35, 0.035, 0.035)),
          "wrist_a.obj": box_obj((0.0, -0.03, -0.03), (0.08, 0.03, 0.03)),
          "wrist_b.obj": box_obj((0.0, -0.03, -0.03), (0.06, 0.03, 0.03)),
          "flange.obj": box_obj((0.0, -0.04, -0.02), (0.06, 0.04, 0.02))}
ARM6_MESH = ARM6.replace("  <worldbody>", "  <asset>\n" + "".join(
    f'    <mesh name="{f[:-4]}" file="{f}"/>\n' for f in MESHES) + "  </asset>\n  <worldbody>")
for body, geom in [("turret", '<geom type="cylinder" size="0.07 0.05" mass="2.5"/>'),
                   ("upper", '<geom type="capsule" fromto="0 0 0 0 0 0.4" size="0.045" mass="3"/>'),
                   ("fore", '<geom type="capsule" fromto="0 0 0 0.35 0 0" size="0.035" mass="1.8"/>'),
                   ("wrist_a", '<geom type="capsule" fromto="0 0 0 0.08 0 0" size="0.03" mass="0.6"/>'),
                   ("wrist_b", '<geom type="cylinder" fromto="0 0 0 0.06 0 0" size="0.03" mass="0.4"/>'),
                   ("flange", '<geom type="box" pos="0.03 0 0" size="0.03 0.04 0.02" mass="0.5"/>')]:
    mass = geom.split('mass="')[1].split('"')[0]
    ARM6_MESH = ARM6_MESH.replace(geom, f'<geom type="mesh" mesh="{body}" mass="{mass}"/>\n'
                                  f'      <geom type="mesh" mesh="{body}" contype="0" conaffinity="0" group="2" '
                                  'density="0" rgba="0.7 0.7 0.7 1"/>')

# the arm on torque motors (no servo loop: it swings under gravity), logged at 1 kHz from a 1 ms
# model; a 0.4 kg tool on the flange the model leaves out
ARM6_MOTORS = ARM6.replace('timestep="0.002"', 'timestep="0.001"').replace(
    '<position dampratio="1" ctrlrange="-0.8 0.8"/>', '<motor ctrlrange="-1 1"/>')
GEARS = {"base": 8, "shoulder": 25, "elbow": 12, "wrist1": 3, "wrist2": 1, "wrist3": 1}
ARM6_MOTORS = re.sub(r'<position name="p_(\w+)" joint="\1" kp="\d+"/>',
                     lambda x: f'<motor name="m_{x[1]}" joint="{x[1]}" gear="{GEARS[x[1]]}"/>', ARM6_MOTORS)
ARM6_TOOL = ARM6_MOTORS.format(truth="").replace(
    '<geom type="box" pos="0.03 0 0" size="0.03 0.04 0.02" mass="0.5"/>',
    '<geom type="box" pos="0.03 0 0" size="0.03 0.04 0.02" mass="0.5"/>\n'
    '                <geom type="sphere" pos="0.1 0 0" size="0.03" mass="0.4"/>')

# ... and as the refusal of the first asks: the turret a capsule (which MJX collides with a box)
CAPSULE_TURRET = ('<geom type="cylinder" size="0.07 0.05" mass="2.5"/>', '<geom type="capsule" size="0.07 0.05" mass="2.5"/>')
ARM6_MOTORS_CAPSULE = ARM6_MOTORS.replace(*CAPSULE_TURRET)
ARM6_TOOL_CAPSULE = ARM6_TOOL.replace(*CAPSULE_TURRET)

# a leg on a test rig: its base on a vertical rail, the foot on the floor (contacts that happen),
# hip and knee on position servos crouching and pushing within a stance
HOPPER_RIG = """<mujoco model="hopper_rig">
  <compiler angle="radian"/>
  <option timestep="0.001" integrator="implicitfast"/>
  <default><joint damping="0.1" armature="0.01"/><position kp="150" kv="4"/></default>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="base" pos="0 0 0.55">
      <joint name="rail" type="slide" axis="0 0 1" damping="2" {truth}/>
      <geom type="box" size="0.1 0.05 0.05" mass="3"/>
      <body name="thigh" pos="0 0 -0.05">
        <joint name="hip" axis="0 1 0" range="-1.5 1.5"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.25" size="0.03" mass="0.8"/>
        <body name="shank" pos="0 0 -0.25">
          <joint name="knee" axis="0 1 0" range="-2.5 0"/>
          <geom type="capsule" fromto="0 0 0 0 0 -0.25" size="0.025" mass="0.4"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="hip" joint="hip" ctrlrange="0.2 0.8"/>
    <position name="knee" joint="knee" ctrlrange="-1.6 -0.4"/>
  </actuator>
</mujoco>"""

# name: (model text, the truth for {truth}, words, drive, extras, training recordings)
PROBES = {
    "arm6_position_elbow_friction": (ARM6, 'frictionloss="1.5"', "coulomb_friction@elbow 1.5 N m (6 joints, "
                                     "position servos)", "multisine", {"period": 0.004}, 2),
    "arm6_position_heavier_forearm": (ARM6, "", "the forearm 2.16 kg where the model says 1.8 (a parameter, no "
                                      "missing effect)", "multisine", {"period": 0.004, "plant": ARM6_HEAVY_FORE}, 2),
    "arm6_mesh_links_elbow_friction": (ARM6_MESH, 'frictionloss="1.5"', "coulomb_friction@elbow 1.5 N m (the arm "
                                       "written with mesh links)", "multisine", {"period": 0.004, "files": MESHES}, 2),
    "arm6_motors_1khz_tool": (ARM6_MOTORS, "", "mass_offset@flange: a 0.4 kg tool 0.1 m out (torque motors, 1 kHz "
                              "log)", "multisine", {"period": 0.001, "plant": ARM6_TOOL}, 2),
    "arm6_motors_1khz_tool_capsule_turret": (ARM6_MOTORS_CAPSULE, "", "mass_offset@flange: a 0.4 kg tool 0.1 m out "
                                             "(the turret a capsule)", "multisine",
                                             {"period": 0.001, "plant": ARM6_TOOL_CAPSULE}, 2),
    "hopper_rig_rail_friction": (HOPPER_RIG, 'frictionloss="3"', "coulomb_friction@rail 3 N (a leg on a rail, its "
                                 "foot on the floor)", "multisine", {}, 2),
    "hopper_rig_delay": (HOPPER_RIG, "", "action_delay 0.015 s (a leg on a rail, its foot on the floor)", "multisine",
                         {"delay_s": 0.015}, 2),
    "pendulum_lost_samples_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m (30 "
                                       "samples lost mid-recording)", "multisine", {"drop": (800, 30)}, 2),
}


if __name__ == "__main__":
    third_wave.main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_9", tuple(sys.argv[2:]), PROBES)
