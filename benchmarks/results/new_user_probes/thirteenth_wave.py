"""A thirteenth wave: recordings with the flaws real loggers and lab routines give them.

Each probe records a plant on native MuJoCo as the second wave does (3 recordings of 8 s at 200 Hz,
position noise 1e-3, 2 to train on, the third held out), then spoils the files as a lab's would be:

- an encoder read over a noisy serial line: a few single-sample glitches in each recording (a
  position off by 0.5 rad for one sample, then back), on the second wave's pendulum with a 0.08 N m
  hinge friction; and the same with glitches of 0.05 rad (the size of a missed packet's worth of motion);
- a cheap potentiometer: position noise of 1e-2 rad (ten times the benchmark's largest) on the pendulum;
- a test routine that drives one joint at a time: the gravity-compensated 2-link arm with a
  0.15 N m s/rad damping at the shoulder, the first recording driving the shoulder alone, the
  second the elbow alone, the held-out one both;
- an incremental encoder zeroed anew at each power-up: each recording's angle off by its own
  constant (0, +0.05, -0.04 rad), the pendulum with its friction;
- a rig that rests between bursts: the pendulum driven for 1 s, then left for 1 s (the command 0),
  four times a recording;
- the clean pendulum (the control: the answer on unspoilt files);
- a robot as a user brings it: MuJoCo Menagerie's UR5e, its MJCF as shipped (``ur5e/``), position
  servos driven +-0.3 rad about its home pose (the truth stepped at 0.5 ms, a quarter of the model's
  step), logged at 500 Hz with noise 1e-4 rad, with a
  5 N m friction at the elbow, or with a 1 kg gripper 0.15 m out on the flange that the model leaves out;
  and Menagerie's SO-ARM100 (``so_arm100/``, a LeRobot arm on bus servos) with its commands 16 ms late.

Prints the probes' table and, per probe, the notes that speak of the recordings.
``PYTHONPATH=. python benchmarks/results/new_user_probes/thirteenth_wave.py [WORK] [PROBE ...]``.
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probes import diagnose_and_print  # noqa: E402
from second_wave import GRAVCOMP, PENDULUM, record  # noqa: E402

FRICTION = 'frictionloss="0.08"'
# MuJoCo Menagerie's UR5e as shipped (ur5e/README.md), its visual meshes a tetrahedron each
UR5E_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "ur5e")
UR5E = open(os.path.join(UR5E_DIR, "ur5e.xml")).read()
HOME = [-1.5708, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]
UR5E_DRIVE = {"around": (HOME, [0.3] * 6), "period": 0.002, "plant_dt": 0.0005, "noise": 1e-4}
# ... and its SO-ARM100 (a LeRobot arm on hobby bus servos), as shipped (so_arm100/), its meshes
# (visual, and collision meshes that no recorded pose brings near each other) a tetrahedron each
SO100 = open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "so_arm100", "so_arm100.xml")).read()
SO100_POSE = [0.0, -1.57, 1.57, 1.4, -1.57, 0.8]  # (home, the wrist and jaw kept off their range ends)
SO100_DRIVE = {"around": (SO100_POSE, [0.25] * 6), "period": 0.002, "plant_dt": 0.0005}


# ... and its Franka Emika Panda (franka_panda/): 7 joints on affine `general` servos, the fingers on
# one tendon servo (its command 0-255) and tied by an equality, the implicit integrator
PANDA = open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "franka_panda", "panda.xml")).read()
PANDA_HOME = [0.0, 0.0, 0.0, -1.57079, 0.0, 1.57079, -0.7853]
PANDA_DRIVE = {"around": (PANDA_HOME + [180.0], [0.25] * 7 + [50.0]), "qpos0": PANDA_HOME + [0.028, 0.028],
               "period": 0.002, "plant_dt": 0.0005, "noise": 1e-4}


def write_meshes(work):
    """A tetrahedron under each mesh file the Menagerie models name (OBJ text, binary STL)."""
    import re
    import struct

    os.makedirs(os.path.join(work, "assets"), exist_ok=True)
    faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]

    def tetrahedron(size):
        v = [(0, 0, 0), (size, 0, 0), (0, size, 0), (0, 0, size)]
        obj = "".join(f"v {x} {y} {z}\n" for x, y, z in v) + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)
        stl = b"\0" * 80 + struct.pack("<I", len(faces)) + b"".join(
            struct.pack("<12fH", 0, 0, 0, *v[a], *v[b], *v[c], 0) for a, b, c in faces)
        return obj, stl

    for text in (UR5E, SO100, PANDA):
        for name in re.findall(r'file="(\w+)\.(?:obj|stl)"', text):
            # (the Panda's hand at about its own size, 0.1 m: a payload in a body is searched within
            # twice its geoms' reach, and a 1 cm stand-in would put the held tool out of reach)
            obj, stl = tetrahedron(0.1 if name.startswith("hand") else 0.01)
            if f'file="{name}.obj"' in text:
                open(os.path.join(work, "assets", name + ".obj"), "w").write(obj)
            if f'file="{name}.stl"' in text:
                open(os.path.join(work, "assets", name + ".stl"), "wb").write(stl)
# name: (model text, the truth for {truth}, words, drive, extras, spoil: {what: setting})
PROBES = {
    "pendulum_clean_friction": (PENDULUM, FRICTION, "coulomb_friction@hinge 0.08 N m (clean files)", "multisine",
                                {}, {}),
    "pendulum_glitches_friction": (PENDULUM, FRICTION, "coulomb_friction@hinge 0.08 N m (4 glitches of 0.5 rad "
                                   "a recording)", "multisine", {}, {"glitches": (4, 0.5)}),
    "pendulum_small_glitches_friction": (PENDULUM, FRICTION, "coulomb_friction@hinge 0.08 N m (4 glitches of "
                                         "0.05 rad a recording)", "multisine", {}, {"glitches": (4, 0.05)}),
    "pendulum_potentiometer_friction": (PENDULUM, FRICTION, "coulomb_friction@hinge 0.08 N m (position noise "
                                        "1e-2 rad)", "multisine", {}, {"noise": 1e-2}),
    "pendulum_bursts_friction": (PENDULUM, FRICTION, "coulomb_friction@hinge 0.08 N m (driven 1 s, resting 1 s)",
                                 "multisine", {}, {"bursts": 1.0}),
    "pendulum_rehomed_friction": (PENDULUM, FRICTION, "coulomb_friction@hinge 0.08 N m (the encoder zeroed anew "
                                  "for each recording: offsets 0, +0.05, -0.04 rad)", "multisine", {},
                                  {"offsets": (0.0, 0.05, -0.04)}),
    "ur5e_elbow_friction": (UR5E.replace('<joint name="elbow_joint" class="size3_limited"/>',
                                         '<joint name="elbow_joint" class="size3_limited" {truth}/>'),
                            'frictionloss="5"', "coulomb_friction@elbow_joint 5 N m (Menagerie's UR5e, setpoints "
                            "+-0.3 rad about home, 500 Hz, noise 1e-4 rad)", "multisine", UR5E_DRIVE, {}),
    "ur5e_gripper_payload": (UR5E.replace('<geom class="eef_collision" pos="0 0.08 0" quat="1 1 0 0" size="0.04 0.02"/>',
                                          '<geom class="eef_collision" pos="0 0.08 0" quat="1 1 0 0" size="0.04 0.02"/>'
                                          '{truth}'),
                             # (a body of its own: wrist_3_link gives its <inertial>, so a geom's mass would not count)
                             '<body name="gripper" pos="0 0.15 0"><inertial pos="0 0 0" mass="1.0" '
                             'diaginertia="0.001 0.001 0.001"/></body>',
                             "mass_offset@wrist_3_link 1 kg 0.15 m out (a gripper the model leaves out; the UR5e as "
                             "above)", "multisine", UR5E_DRIVE, {}),
    "so_arm100_bus_delay": (SO100, "", "action_delay 0.016 s (Menagerie's SO-ARM100, its servos' commands 16 ms late "
                            "on the bus; setpoints +-0.25 rad about home, 500 Hz, noise 1e-3 rad)", "multisine",
                            dict(SO100_DRIVE, delay_s=0.016), {}),
    "panda_tool_payload": (PANDA.replace('diaginertia="0.001 0.0025 0.0017"/>', 'diaginertia="0.001 0.0025 0.0017"/>{truth}'),
                           '<body name="tool" pos="0 0 0.12"><inertial pos="0 0 0" mass="0.5" '
                           'diaginertia="0.0002 0.0002 0.0002"/></body>',
                           "0.5 kg held in the hand 0.12 m out along the flange's axis (Menagerie's Panda; setpoints "
                           "+-0.25 rad about home, the gripper 180+-50 of 255, 500 Hz, noise 1e-4 rad)", "multisine",
                           PANDA_DRIVE, {}),
    "gravcomp_arm_one_joint_at_a_time_damping": (GRAVCOMP, 'damping="0.15"', "viscous_damping@j1 0.15 N m s/rad "
                                                 "(the shoulder driven alone, then the elbow; both held out)",
                                                 "multisine", {"excite": [[1, 0], [0, 1], [1, 1]]}, {}),
}


def spoil(paths, how):
    """Rewrite the recordings: ``glitches (n, size)``: n single samples of the first position off
    by +-size; ``offsets``: the first position of each recording shifted by its own constant; ``noise``: more position noise of this standard deviation; ``bursts``: every other
    ``bursts`` seconds, the commands set to 0 (the bursts were recorded that way: see ``main``)."""
    rng = np.random.default_rng(13)
    for p in paths:
        header = open(p).readline().strip().split(",")
        data = np.loadtxt(p, delimiter=",", skiprows=1)
        q = [k for k, n in enumerate(header) if n.startswith("qpos:")]
        if "glitches" in how:
            n, size = how["glitches"]
            rows = rng.choice(np.arange(20, len(data) - 20), n, replace=False)
            data[rows, q[0]] += size * rng.choice([-1.0, 1.0], n)
        if "offsets" in how:  # (one per recording, in order)
            data[:, q[0]] += how["offsets"][paths.index(p)]
        if "noise" in how:
            data[:, q] += rng.normal(0, how["noise"], (len(data), len(q)))
        np.savetxt(p, data, delimiter=",", header=",".join(header), comments="")


def main(work, only=()):
    write_meshes(work)
    print("| probe | truth | named | values | held-out NRMSE before -> after | seconds |")
    print("|---|---|---|---|---|---|")
    said = {}
    for name, (text, truth, words, drive, extras, how) in PROBES.items():
        if only and name not in only:
            continue
        if "bursts" in how:  # the plant sees the rests: the qfrc hook cannot, so the drive is masked in time
            extras = dict(extras, rest=how["bursts"])
        nominal, paths = record(name, text, truth, drive, extras, work)
        spoil(paths, how)
        diagnose_and_print(name, words, nominal, paths, work)
        notes = os.path.join(work, name + "_notes.json")
        if os.path.exists(notes):
            said[name] = [n for n in json.load(open(notes)) if "simulated at" not in n]
    print()
    for name, notes in said.items():
        print(f"- {name}: " + (" / ".join(n[:240] for n in notes) if notes else "no note"))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_13", tuple(sys.argv[2:]))
