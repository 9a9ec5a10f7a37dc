"""What the kept model leaves unexplained (``diagnosis.json``'s ``fit.left``), per case of a list
run by ``diagnosis_independent.py``: the calibration of ``diagnose.LEFT_RATIO``.

    python benchmarks/results/diagnosis_independent/left_over/analyse.py OUT/cases.csv WORK [...]

(pairs of a run's ``cases.csv`` and its ``work=`` folder). Groups: "holds all" -- the answer named
exactly the hidden physics (a parameter-only case answered with no effect), so the kept model holds
every physics of its plant; "misses" -- a hidden effect not named. Prints each case's ratio and
each group's spread.
"""
import csv
import json
import os
import sys

import numpy as np


def rows(cases_csv: str, work: str):
    for r in csv.DictReader(open(cases_csv)):
        path = os.path.join(work, r["case"], "diagnosis", "diagnosis.json")
        if not os.path.exists(path):
            continue
        d = json.load(open(path))
        left, before = d["fit"].get("left"), d["fit"].get("left_before")
        if left is None:
            continue
        truth = set() if r["truth"] == "none" else set(r["truth"].split(" + "))
        named = set() if r["named"] == "none" else set(r["named"].split(" + "))
        group = "holds all" if named == truth else ("misses" if truth - named else "false extra")
        yield dict(case=r["case"], group=group, answer=d["answer"], ratio=left["ratio"],
                   typical=left.get("typical_ratio"), before=before["ratio"],
                   typical_before=before.get("typical_ratio"))


def main(argv):
    out = []
    for cases_csv, work in zip(argv[::2], argv[1::2]):
        out += list(rows(cases_csv, work))
    for r in sorted(out, key=lambda r: (r["group"], r["ratio"])):
        typ = "" if r["typical"] is None else f" typical {r['typical']:8.3g}"
        print(f"{r['group']:12s} {r['case']:58s} {r['answer']:12s} ratio {r['ratio']:8.3g}{typ}   "
              f"(nominal {r['before']:8.3g})")
    print()
    for g in ("holds all", "misses", "false extra"):
        x = np.array([r["ratio"] for r in out if r["group"] == g])
        if len(x):
            q = np.percentile(x, [50, 90, 95, 100])
            print(f"{g}: {len(x)} cases, ratio median {q[0]:.3g}, 90th {q[1]:.3g}, 95th {q[2]:.3g}, max {q[3]:.3g}")
        t = np.array([r["typical"] for r in out if r["group"] == g and r["typical"] is not None])
        if len(t):
            q = np.percentile(t, [50, 90, 95, 100])
            print(f"{g}: {len(t)} cases, typical-segment ratio median {q[0]:.3g}, 90th {q[1]:.3g}, 95th {q[2]:.3g}, "
                  f"max {q[3]:.3g}")
    x = np.array([r["before"] for r in out])
    print(f"the model files as given (every case): ratio median {np.median(x):.3g}, "
          f"{np.mean(x > 10):.0%} over 10")


if __name__ == "__main__":
    main(sys.argv[1:])
