"""A sixth wave: a geared motor's rotor inertia left out of the model (MuJoCo's ``armature`` in the
plant, none in the model), on a pendulum and on both joints of a horizontal 2-link arm; each run
on the defaults, with ``rotor_inertia`` asked for, and with ``rotor=true`` (a named band fitted
again as its joint's rotor inertia). Recorded and printed as the second wave's.
``PYTHONPATH=. python benchmarks/results/new_user_probes/sixth_wave.py [WORK] [PROBE ...]``.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import third_wave  # noqa: E402  (its runner, the same table)
from probes import diagnose_and_print  # noqa: E402
from second_wave import PENDULUM, record  # noqa: E402

ARM = third_wave.ARM.replace('<joint name="j1" axis="0 0 1" damping="0.05"/>',
                             '<joint name="j1" axis="0 0 1" damping="0.05" {truth}/>').replace(
    '<joint name="j2" axis="0 0 1" damping="0.02"/>', '<joint name="j2" axis="0 0 1" damping="0.02" {truth}/>')

# name: (model text, the truth for {truth}, words, drive, extras, training recordings)
PROBES = {
    "pendulum_rotor_armature": (PENDULUM, 'armature="0.01"', "rotor inertia 0.01 kg m^2 (armature; a geared motor)",
                                "multisine", {}, 2),
    "arm_rotor_armature": (ARM, 'armature="0.02"', "rotor inertia 0.02 kg m^2 on both joints", "multisine", {}, 2),
}


def main(work, only=()):
    from sim2real.sysid.diagnose import EFFECTS

    third_wave.main(work, only, PROBES)
    for name, (text, truth, words, drive, extras, train) in PROBES.items():
        if not only or name in only:
            nominal, paths = record(name, text, truth, drive, extras, work)
            diagnose_and_print(name + "_asked", words, nominal, paths, work, train,
                               effects=tuple(EFFECTS) + ("rotor_inertia",))
            diagnose_and_print(name + "_rotor", words, nominal, paths, work, train, rotor=True)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_6", tuple(sys.argv[2:]))
