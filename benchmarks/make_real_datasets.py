"""How the bundled real datasets were converted (run once; the results are in sim2real/sysid/data/).

    python benchmarks/make_real_datasets.py dfki=PATH/torque_limited_simple_pendulum

DFKI torque-limited simple pendulum (BSD-3-Clause, github.com/dfki-ric-underactuated-lab/
torque_limited_simple_pendulum, commit ed17ea2d): two swing-ups recorded on the real pendulum
(AK80-6 quasi-direct-drive motor), each a CSV of time, position, velocity and the torque the
motor reported (from its current). Converted to the recording format: ``qpos:hinge`` (rad),
``qvel:hinge`` (rad/s), ``ctrl:motor`` = the measured torque (N m), the input the mechanics
received, as the lab's own identification used it. The SAC run's first row is dropped (the
logger's first interval is 22 ms, the others 5 ms).
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


def _git_csv(repo: str, path: str) -> np.ndarray:
    text = subprocess.run(["git", "--git-dir", repo, "show", f"HEAD:{path}"], capture_output=True, text=True,
                          check=True).stdout
    rows = [r.split(",") for r in text.strip().splitlines()[1:]]
    return np.array(rows, float)


def _write(path, cols: dict):
    names = list(cols)
    np.savetxt(path, np.column_stack([cols[n] for n in names]), delimiter=",", header=",".join(names),
               comments="", fmt="%.9g")


def dfki(repo: str) -> None:
    out = os.path.join(DATA, "dfki_pendulum")
    runs = {"energy_shaping": ("results/control_method_energy_shaping/data_measured.csv", 0),
            "sac": ("results/control_method_sac/data_measured.csv", 1)}
    for name, (path, skip) in runs.items():
        a = _git_csv(repo, path)[skip:]
        t, q, v, tau = a.T
        _write(os.path.join(out, f"{name}.csv"), {"time": t, "qpos:hinge": q, "qvel:hinge": v, "ctrl:motor": tau})
        print(name, len(t), "samples", f"{t[-1] - t[0]:.1f} s")


@dataclasses.dataclass
class Settings:
    """dfki: git folder of dfki-ric-underactuated-lab/torque_limited_simple_pendulum."""
    dfki: str = ""


def main(args: Settings):
    if args.dfki:
        dfki(args.dfki)


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
