"""How the bundled real datasets were converted (run once; the results are in sim2real/sysid/data/).

    python benchmarks/make_real_datasets.py dfki=PATH/torque_limited_simple_pendulum
    python benchmarks/make_real_datasets.py ibm=PATH/tiny-differentiable-simulator
    python benchmarks/make_real_datasets.py kuka=PATH/FloBaRoID

DFKI torque-limited simple pendulum (BSD-3-Clause, github.com/dfki-ric-underactuated-lab/
torque_limited_simple_pendulum, commit ed17ea2d): two swing-ups recorded on the real pendulum
(AK80-6 quasi-direct-drive motor), each a CSV of time, position, velocity and the torque the
motor reported (from its current). Converted to the recording format: ``qpos:hinge`` (rad),
``qvel:hinge`` (rad/s), ``ctrl:motor`` = the measured torque (N m), the input the mechanics
received, as the lab's own identification used it. The SAC run's first row is dropped (the
logger's first interval is 22 ms, the others 5 ms).

IBM Double Pendulum Chaotic (CDLA-Sharing-1.0; Asseman, Kornuta & Ozcan 2018; the CSVs as
redistributed with their licence in github.com/erwincoumans/tiny-differentiable-simulator,
``data/ibm-double-pendulum/original/dpc_dataset_csv``): a free double pendulum filmed at 400 Hz,
each row the pixel positions (x right, y down) of three markers -- pivot, elbow, tip. The angles
are read from the markers (the camera lies on its side: gravity is the image's +x):
``qpos:shoulder`` = the first arm from the downward vertical, ``qpos:elbow`` = the second arm
relative to the first (rad, unwrapped: the arms spin whole turns).
Runs 0, 1 and 2, their first ``ibm_seconds`` seconds each.

KUKA LWR4+ (LGPL-3.0, the licence of github.com/kjyv/FloBaRoID, whose ``data/KUKA/HW`` holds
them; Bethge et al., RAAD 2017): three excitation runs of a real 7-joint KUKA LWR4+ at IIT, 25 s
each, logged at ~200 Hz through KUKA's interface (positions, velocities and the joint torque
sensors' readings). Runs 1 and 2 are the same trajectory recorded 29 min apart, run 3 another. The
files are Git LFS pointers today; the blobs of 2016 (commits 4e2e5a2, e6c077e) are the data.
Converted: ``qpos:lwr_<i>_joint`` (rad), ``qvel:lwr_<i>_joint`` (rad/s, the robot's own),
``ctrl:lwr_<i>_motor`` = the measured joint torque (N m), linearly interpolated from the logger's
jittered stamps (3.4-6.5 ms) onto a uniform 5 ms grid starting at 0. The nominal MJCF is the
repository's ``model/kuka_lwr4.urdf`` (inertias "from CentroEPiaggio/kuka-lwr, with
modifications"; the URDF's joint damping and friction become MuJoCo's ``damping`` and
``frictionloss``) compiled by MuJoCo with its meshes left out (visual only), a duplicated
``<origin>`` removed, and a torque motor (gear 1, the URDF's effort limit) added on every joint.
"""
from __future__ import annotations

import dataclasses
import os
import subprocess
import sys

import numpy as np

from sim2real.common.cli import settings

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "sim2real", "sysid", "data")


def _git_show(repo: str, path: str, rev: str = "HEAD") -> bytes:
    """A file of ``repo`` (a git folder) at ``rev``, as bytes."""
    return subprocess.run(["git", "--git-dir", repo, "show", f"{rev}:{path}"], capture_output=True,
                          check=True).stdout


def _git_csv(repo: str, path: str, header: bool = True) -> np.ndarray:
    text = _git_show(repo, path).decode()
    rows = [r.split(",") for r in text.strip().splitlines()[1 if header else 0:]]
    return np.array(rows, float)


def _write(path, cols: dict):
    names = list(cols)
    np.savetxt(path, np.column_stack([cols[n] for n in names]), delimiter=",", header=",".join(names),
               comments="", fmt="%.9g")


def ibm(repo: str, seconds: float) -> None:
    out = os.path.join(DATA, "ibm_double_pendulum")
    for run in (0, 1, 2):
        a = _git_csv(repo, f"data/ibm-double-pendulum/original/dpc_dataset_csv/{run}.csv",
                     header=False)[: int(round(seconds * 400))]
        x0, y0, x1, y1, x2, y2 = a.T
        # The camera is mounted sideways: gravity points along the image's +x axis (every run's
        # swing settles about atan2(dx, dy) = 1.55-1.56 rad, i.e. pi/2 less a 0.7 degree tilt), so
        # the angle from hanging straight down is atan2(dx, dy) - pi/2. The tilt is left in the
        # data (a sensor offset of ~0.01 rad on the shoulder), as a user's camera would leave it.
        upper = np.unwrap(np.arctan2(x1 - x0, y1 - y0))
        elbow = np.unwrap(np.arctan2(x2 - x1, y2 - y1)) - upper  # relative: the camera's turn cancels
        shoulder = upper - np.pi / 2
        t = np.arange(len(a)) / 400.0
        _write(os.path.join(out, f"run{run}.csv"), {"time": t, "qpos:shoulder": shoulder, "qpos:elbow": elbow})
        print(f"run{run}", len(t), "samples", f"{t[-1]:.1f} s")


def dfki(repo: str) -> None:
    out = os.path.join(DATA, "dfki_pendulum")
    runs = {"energy_shaping": ("results/control_method_energy_shaping/data_measured.csv", 0),
            "sac": ("results/control_method_sac/data_measured.csv", 1)}
    for name, (path, skip) in runs.items():
        a = _git_csv(repo, path)[skip:]
        t, q, v, tau = a.T
        _write(os.path.join(out, f"{name}.csv"), {"time": t, "qpos:hinge": q, "qvel:hinge": v, "ctrl:motor": tau})
        print(name, len(t), "samples", f"{t[-1] - t[0]:.1f} s")


KUKA_RUNS = {1: "4e2e5a2", 2: "4e2e5a2", 3: "e6c077e"}  # the last commits holding the npz, not an LFS pointer


def kuka(repo: str) -> None:
    import io
    import re

    import mujoco

    out = os.path.join(DATA, "kuka_lwr4")
    os.makedirs(out, exist_ok=True)
    urdf = _git_show(repo, "model/kuka_lwr4.urdf").decode()
    urdf = re.sub(r"<(visual|collision)>.*?</\1>", "", urdf, flags=re.S)  # meshes: looks only
    urdf = urdf.replace('<origin rpy="0 0 0" xyz="-0.25 0 1"/>\n    <origin rpy="0 0 0" xyz="0 0 0"/>',
                        '<origin rpy="0 0 0" xyz="-0.25 0 1"/>')  # MuJoCo refuses a repeated element
    effort = dict(re.findall(r'<joint name="(lwr_\d_joint)".*?<limit effort="([\d.]+)"', urdf, flags=re.S))
    spec = mujoco.MjSpec.from_string(urdf)
    spec.modelname = "kuka_lwr4"
    for j, e in effort.items():
        spec.add_actuator(name=j.replace("joint", "motor"), target=j, trntype=mujoco.mjtTrn.mjTRN_JOINT,
                          ctrllimited=True, ctrlrange=[-float(e), float(e)])
    spec.compile()
    with open(os.path.join(out, "kuka_lwr4.xml"), "w") as f:
        f.write("<!-- KUKA LWR4+ from FloBaRoID's model/kuka_lwr4.urdf (LGPL-3.0), compiled by MuJoCo; see\n"
                "     benchmarks/make_real_datasets.py. The URDF's damping/friction are the joints' damping and\n"
                "     frictionloss; a torque motor on every joint. -->\n" + spec.to_xml())
    joints = sorted(effort)
    for run, commit in KUKA_RUNS.items():
        z = np.load(io.BytesIO(_git_show(repo, f"data/KUKA/HW/measurements_{run}.npz", commit)))
        t = z["times"] - z["times"][0]
        grid = np.arange(0.0, t[-1], 0.005)
        cols = {"time": grid}
        for key, kind in (("positions", "qpos:{}"), ("velocities", "qvel:{}"), ("torques", "ctrl:{}")):
            for i, j in enumerate(joints):
                name = j.replace("joint", "motor") if kind.startswith("ctrl") else j
                cols[kind.format(name)] = np.interp(grid, t, z[key][:, i])
        _write(os.path.join(out, f"run{run}.csv"), cols)
        print(f"run{run}", len(grid), "samples", f"{grid[-1]:.1f} s")


@dataclasses.dataclass
class Settings:
    """dfki: git folder of dfki-ric-underactuated-lab/torque_limited_simple_pendulum; ibm: git folder
    of erwincoumans/tiny-differentiable-simulator; ibm_seconds: how much of each IBM run to keep; kuka:
    git folder of kjyv/FloBaRoID."""
    dfki: str = ""
    ibm: str = ""
    kuka: str = ""
    ibm_seconds: float = 20.0


def main(args: Settings):
    if args.dfki:
        dfki(args.dfki)
    if args.ibm:
        ibm(args.ibm, args.ibm_seconds)
    if args.kuka:
        kuka(args.kuka)


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
