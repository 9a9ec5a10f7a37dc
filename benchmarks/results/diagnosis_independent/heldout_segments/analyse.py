"""The held-out walk re-run offline on the device run's stored errors (``.venv/bin/python
benchmarks/results/diagnosis_independent/heldout_segments/analyse.py``; reads ``device/*.jsonl.gz``
and ``local_2core/*.jsonl.gz``, prints what ``analyse.txt`` holds).

The walk (``diagnose.heldout_walk``) keeps a step while it lowers the held-out error of the step
before; the error is the report's pooled NRMSE, which a few badly predicted segments can rule
(the combos list's 6115: a start at rest, mispredicted by every model). Here the same walk is run
on other aggregates of the stored per-segment errors (``heldout_segments`` of each step,
``per_segment_before`` of the model file), and every case whose kept steps would move is listed,
gained or lost against the truth. First the replica is checked: on the pooled errors it must
keep what the diagnosis kept (a case whose energy step added a step cannot be replayed: the
steps after the kept one were replaced; it is left out)."""
import dataclasses
import glob
import gzip
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", ".."))
from sim2real.sysid.diagnose import DiagnoseConfig, heldout_walk  # noqa: E402

CFG = DiagnoseConfig()


def walk(ho, nominal, joins, cfg=CFG):
    """``diagnose.heldout_walk`` (pooled errors only; its defaults unless ``cfg``), on any per-step
    error ``ho``."""
    return heldout_walk(list(ho), nominal, np.ones((len(ho), 1)), joins, cfg)


def effects(label: str) -> list[str]:
    return [] if label == "none" else sorted(x.strip() for x in label.split("+"))


def aggregates(seg: np.ndarray) -> dict:
    """``{name: [models]}`` error per model (the model file first) from ``seg [models, segments]``."""
    n = seg.shape[1]
    best = seg.min(axis=0)   # how well the best model predicts each segment
    out = {"RMS of segments": np.sqrt(np.mean(seg ** 2, axis=1)),
           "mean of segments": seg.mean(axis=1),
           "median of segments": np.median(seg, axis=1)}
    for share in (0.05, 0.1, 0.2):
        drop = int(np.floor(share * n))
        kept = np.argsort(best)[: n - drop]
        out[f"RMS without the {share:.0%} worst-predicted"] = np.sqrt(np.mean(seg[:, kept] ** 2, axis=1))
    return out


def main():
    rows = []
    for path in sorted(glob.glob(os.path.join(HERE, "device", "*.jsonl.gz"))
                       + glob.glob(os.path.join(HERE, "local_2core", "*.jsonl.gz"))):
        rows += [json.loads(line) for line in gzip.open(path, "rt")]
    usable, skipped, mismatch = [], [], []
    for r in rows:
        steps = r.get("steps") or []
        if not steps or r.get("per_segment_before") is None:
            skipped.append(r["case"])
            continue
        ho = [s["heldout_nrmse"] for s in steps]
        joins = [bool(s.get("joins_next")) for s in steps]
        kept = max(k for k, s in enumerate(steps) if s["kept"])
        if walk(ho, r["before"], joins) != kept:
            mismatch.append(r["case"])
            continue
        usable.append((r, kept, joins))
    right = sum(effects(r_["steps"][k]["model"]) == r_["truth"] for r_, k, _ in usable)
    print(f"{len(rows)} cases; {len(usable)} replayed (the pooled walk keeps what the diagnosis kept; "
          f"{right} of them right by their kept steps); {len(mismatch)} not replayable (an energy step "
          f"or the refit rule: {', '.join(c.split('_')[0] for c in mismatch)}); {len(skipped)} without steps\n")
    print("Where the misses are (by the kept steps against the truth):")
    where = {}
    for r, kept, _ in usable:
        steps, truth = r["steps"], set(r["truth"])
        named = set(effects(steps[kept]["model"]))
        if named == truth:
            continue
        ever = set().union(*(set(effects(s["model"])) for s in steps))
        if any(effects(s["model"]) == r["truth"] for s in steps):
            why = "the true model was a step; the walk kept another"
        elif not truth:
            why = "parameter-only: a false effect kept"
        elif not truth & ever:
            why = "no true effect ever selected"
        elif named < truth:
            why = "part of the truth named, the rest never selected"
        elif named & truth:
            why = "part of the truth named, with a false effect"
        else:  # (a true effect was a step: ``truth & ever``)
            why = "a true effect selected, then dropped with what followed it"
        where.setdefault(why, []).append(r["case"].split("_")[0] + ("d" if len(truth) > 1 else ""))
    for why, cases in sorted(where.items(), key=lambda x: -len(x[1])):
        print(f"  {len(cases):3d} {why}: {' '.join(cases)}")
    print("  (d: a two-effect case)\n")
    names = list(aggregates(np.ones((2, 10))))
    for name in names:
        moved = []
        for r, kept, joins in usable:
            steps = r["steps"]
            seg = np.array([r["per_segment_before"]] + [s["heldout_segments"] for s in steps])
            a = aggregates(seg)[name]
            k = walk(list(a[1:]), a[0], joins)
            if k != kept:
                was, now = effects(steps[kept]["model"]), effects(steps[k]["model"])
                mark = ("GAINED" if now == r["truth"] else "LOST" if was == r["truth"] else "moved")
                moved.append(f"    {mark:6s} {r['case']}: {steps[kept]['model']} -> {steps[k]['model']}")
        g, lo = sum("GAINED" in m for m in moved), sum("LOST" in m for m in moved)
        print(f"{name}: {len(moved)} moved, {g} gained, {lo} lost")
        print("\n".join(moved))
    gains(usable)


def gains(usable):
    """The walk's two gains swept on the pooled errors: right answers, and the cases that move."""
    print("\nThe walk's gains swept (pooled NRMSE; defaults heldout_gain_first "
          f"{CFG.heldout_gain_first}, heldout_gain {CFG.heldout_gain}):")
    for first in (0.0, 0.01, 0.02, 0.05):
        for later in (0.02, 0.05, 0.08, 0.1, 0.15, 0.2, 0.3):
            cfg = dataclasses.replace(CFG, heldout_gain_first=first, heldout_gain=later)
            right, moved = 0, []
            for r, kept, joins in usable:
                steps = r["steps"]
                k = walk([s["heldout_nrmse"] for s in steps], r["before"], joins, cfg)
                ok = effects(steps[k]["model"]) == r["truth"]
                right += ok
                if ok != (effects(steps[kept]["model"]) == r["truth"]):
                    moved.append(("+" if ok else "-") + r["case"].split("_")[0])
            print(f"  first {first:g}, later {later:g}: {right} right {' '.join(moved)}")


if __name__ == "__main__":
    main()
