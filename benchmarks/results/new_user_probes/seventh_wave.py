"""A seventh wave: friction and torque the library has no exact name for, written here as joint
forces applied at every physics step of native MuJoCo (``second_wave.record``'s ``qfrc``):

- Stribeck friction on a motor-driven pendulum: a static level of 0.12 N m falling to a Coulomb
  level of 0.08 N m above about 0.1 rad/s (smoothed through zero over 0.01 rad/s). The nearest name
  is ``coulomb_friction`` (a level between the two is what a user would take as right).
- Cogging torque on a pendulum whose motor cannot swing it over the top: 0.05 N m x sin(12 q) (a
  12-slot motor's detent torque). Nothing in the library is periodic in the angle: the honest answers are ``none``
  or ``inconclusive``; a named effect is a false one.

Recorded and printed as the second wave's (3 recordings of 8 s at 200 Hz, position noise 1e-3, 2 to
train on, the third held out).
``PYTHONPATH=. python benchmarks/results/new_user_probes/seventh_wave.py [WORK] [PROBE ...]``.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import third_wave  # noqa: E402  (its runner, the same table)
from second_wave import PENDULUM  # noqa: E402

# the pendulum on a weaker motor (0.6 N m, half its weight's largest torque): it swings, never
# over the top, through several of a 12-slot motor's detent periods
SMALL_SWING = PENDULUM.replace('ctrlrange="-2 2"', 'ctrlrange="-0.6 0.6"')


def stribeck(qpos, qvel, fs=0.12, fc=0.08, vs=0.1, eps=0.01):
    """Stribeck friction (N m) opposing the velocity ``qvel`` (rad/s)."""
    v = qvel[0]
    return np.array([-(fc + (fs - fc) * np.exp(-(v / vs) ** 2)) * np.tanh(v / eps)])


def cogging(qpos, qvel, amp=0.05, slots=12):
    """A motor's detent torque (N m), periodic in the angle ``qpos`` (rad)."""
    return np.array([-amp * np.sin(slots * qpos[0])])


# name: (model text, the truth for {truth}, words, drive, extras, training recordings)
PROBES = {
    "pendulum_stribeck_friction": (PENDULUM, "", "Stribeck friction: 0.12 N m static, 0.08 N m Coulomb above "
                                   "0.1 rad/s (nearest name: coulomb_friction@hinge)", "multisine",
                                   {"qfrc": stribeck}, 2),
    "pendulum_cogging_torque": (SMALL_SWING, "", "cogging torque 0.05 N m x sin(12 q) (no name for it: none "
                                "or inconclusive is honest)", "multisine", {"qfrc": cogging}, 2),
}


if __name__ == "__main__":
    third_wave.main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_7", tuple(sys.argv[2:]), PROBES)
