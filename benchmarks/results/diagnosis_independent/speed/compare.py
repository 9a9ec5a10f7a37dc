"""Answers of a run of ``heldout_segments/run_device.py`` against stored rows of the same cases.

    python compare.py NEW.jsonl[.gz] REF.jsonl[.gz] [REF2 ...]

A case is the same when its named effects, their being right and its held-out error (to 1e-6,
relative) are the reference's; prints each case that is not and the median ratio of the times.
"""
import gzip
import json
import sys

import numpy as np


def rows(path):
    with (gzip.open(path, "rt") if path.endswith(".gz") else open(path)) as f:
        return [json.loads(line) for line in f]


def main(new_path, *refs):
    ref = {r["case"]: r for path in refs for r in rows(path)}
    same, diff, ratios = 0, 0, []
    new = rows(new_path)
    for r in new:
        o = ref.get(r["case"])
        if o is None:
            print("no reference row:", r["case"])
            continue
        a, b = (sorted(r["named"] or []), r["correct"]), (sorted(o["named"] or []), o["correct"])
        close = (r.get("after") is not None and o.get("after") is not None
                 and abs(r["after"] - o["after"]) <= 1e-6 * max(1.0, abs(o["after"])))
        if a == b and close:
            same += 1
        else:
            diff += 1
            print("DIFFERENT", r["case"], a, b, r.get("after"), o.get("after"))
        if r.get("seconds") and o.get("seconds"):
            ratios.append(r["seconds"] / o["seconds"])
    print(f"same {same} different {diff} of {len(new)}; median time ratio "
          f"{np.median(ratios) if ratios else float('nan'):.3f}")


if __name__ == "__main__":
    main(*sys.argv[1:])
