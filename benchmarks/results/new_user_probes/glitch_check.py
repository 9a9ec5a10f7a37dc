"""False glitches: the single-sample glitch repair (``recordings._glitches``) run over every measured
position of the tuning lists' recordings and of the bundled real recordings, as logged.

``PYTHONPATH=. python benchmarks/results/new_user_probes/glitch_check.py [WORK] [SPLIT ...]``
(default splits: tuning extra combos pairs servo pd; the cases are generated into WORK/<split>/
where they are not there already). Prints every sample it would repair (none is expected: these
recordings have no glitches) and the count of files and samples looked at.
"""
import glob
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
sys.path.insert(0, os.path.join(ROOT, "benchmarks"))
import diagnosis_independent as di  # noqa: E402
import mujoco  # noqa: E402
import sysid_cases  # noqa: E402

from sim2real.sysid import recordings as R  # noqa: E402


def check(path, model):
    """The glitches the loader would repair in one file (its notes), and its samples of positions."""
    found = [n for r in R.load_pieces(path, model) for n in r.notes if "glitch" in n]
    cols = R._read_table(path)
    return found, sum(len(v) for k, v in cols.items() if k.startswith("qpos:"))


def main(work, splits):
    files = samples = 0
    for split in splits:
        for case in sysid_cases.split_cases(split):
            folder = os.path.join(work, split, case.label)
            os.makedirs(folder, exist_ok=True)
            di.case_files(case, folder)
            model = mujoco.MjModel.from_xml_path(os.path.join(folder, "nominal.xml"))
            for p in sorted(glob.glob(os.path.join(folder, "*.csv"))):
                found, n = check(p, model)
                files, samples = files + 1, samples + n
                for f in found:
                    print(f"{split}/{case.label}: {f}")
    data = os.path.join(ROOT, "sim2real", "sysid", "data")
    for folder, model, pattern in (("emps", "emps_nominal.xml", "*.mat"), ("dfki_pendulum", "pendulum.xml", "*.csv"),
                                   ("ibm_double_pendulum", "double_pendulum.xml", "*.csv"),
                                   ("kuka_lwr4", "kuka_lwr4.xml", "*.csv")):
        m = mujoco.MjModel.from_xml_path(os.path.join(data, folder, model))
        for p in sorted(glob.glob(os.path.join(data, folder, pattern))):
            found, n = check(p, m)
            files, samples = files + 1, samples + n
            for f in found:
                print(f"{folder}: {f}")
    print(f"{files} files, {samples} position samples looked at")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/glitch_check",
         tuple(sys.argv[2:]) or ("tuning", "extra", "combos", "pairs", "servo", "pd"))
