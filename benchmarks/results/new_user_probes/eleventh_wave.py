"""An eleventh wave: joints with ranges, as arm makers give them (MuJoCo limits a joint that has a
``range``; menagerie's arms all have them), on native MuJoCo:

- the ninth wave's 6-joint arm on `position` servos with a Coulomb friction of 1.5 N m on the elbow,
  its joints given ranges in degrees (base and wrist roll +-170, shoulder +-120, elbow +-150, wrist
  pitches +-120 and +-170) that the recorded motion (within +-0.8 rad of the upright pose) never
  reaches;
- the ninth wave's leg on a test rig (hip and knee with ranges, the foot on the floor), its rail's
  Coulomb friction of 3 N.

Run to measure the diagnosis with the limits no recorded position comes near left out of the
simulation (``System.limits_clear``): ``eleventh_wave.txt`` has this code's table and the code's
before it (the same recordings). Recorded and printed as the second wave's (3 recordings of 8 s,
position noise 1e-3, 2 to train on, the third held out).
``PYTHONPATH=. python benchmarks/results/new_user_probes/eleventh_wave.py [WORK] [PROBE ...]``.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import third_wave  # noqa: E402  (its runner, the same table)
from ninth_wave import ARM6, PROBES as NINTH  # noqa: E402

RANGES = {"base": 170, "shoulder": 120, "elbow": 150, "wrist1": 120, "wrist2": 170, "wrist3": 170}
ARM6_RANGED = ARM6
for joint, deg in RANGES.items():
    ARM6_RANGED = ARM6_RANGED.replace(f'<joint name="{joint}" ', f'<joint name="{joint}" range="-{deg} {deg}" ')
assert ARM6_RANGED.count(' range="') == 6

PROBES = {
    "arm6_ranged_elbow_friction": (ARM6_RANGED, 'frictionloss="1.5"', "coulomb_friction@elbow 1.5 N m (6 joints "
                                   "with ranges, position servos)", "multisine", {"period": 0.004}, 2),
    "hopper_rig_rail_friction": NINTH["hopper_rig_rail_friction"],
}

if __name__ == "__main__":
    third_wave.main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_11", tuple(sys.argv[2:]), PROBES)
