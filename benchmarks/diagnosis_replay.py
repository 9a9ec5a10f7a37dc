"""How the selection thresholds were chosen: replay decision rules over permissive runs.

    python benchmarks/diagnosis_independent.py split=tuning work=CASES diagnose.min_gain=0.01 diagnose.min_t=1.0
    python scripts/diagnose.py out=EMPS_PERMISSIVE min_gain=0.01 min_t=0   # the bundled EMPS data
    python benchmarks/diagnosis_replay.py CASES EMPS_PERMISSIVE ["(gain, t, level, stats, strong)"]

A permissive run records, for every selection round, each fitted candidate's per-segment
validation errors; a stricter rule's outcome follows from them (a rule that picks a different
effect than the recorded path stops there: what it would do next was not recorded). Only the
tuning half and EMPS are read. Prints the rules ranked by: no effect on parameter-only cases,
EMPS named, cases named exactly.
"""
import glob
import itertools
import json
import os
import sys

import numpy as np

import sysid_cases as sc

root = sys.argv[1]
emps_run = sys.argv[2]
cases = {c.label: c for c in sc.build_cases()}

def tstat(d):
    if len(d) < 3 or np.std(d) == 0: return np.inf if np.mean(d) > 0 else 0.0
    return np.mean(d) / (np.std(d, ddof=1) / np.sqrt(len(d)))

def load(f, kind, truth, label):
    d = json.load(open(f))
    rounds = []
    for rnd in d["rounds"]:
        base = np.array(rnd["base_validation_segments"]); npt = rnd["residuals_per_segment"]
        cands = []
        for r in rnd["candidates"]:
            if "validation_segments" not in r: continue
            key = r["effect"] if r["effect"] == "action_delay" else f"{r['effect']}@{r['target']}"
            v = np.array(r["validation_segments"])
            ratio = v.sum() / base.sum()
            st = {"raw": tstat(base - v)}
            for kappa in (0.1, 1.0, 10.0):
                st[kappa] = tstat(np.log((base + kappa * npt + 1e-12) / (v + kappa * npt + 1e-12)))
            st["sign"] = (np.mean(base > v) - 0.5) * 2 * np.sqrt(len(v))  # sign test z
            level = base.sum() / (npt * len(base))
            cands.append((key, ratio, st, level))
        rounds.append(cands)
    path = [s.split(" + ")[-1] for s in [x["model"] for x in d["steps"]][1:]]
    return (label, kind, truth, rounds, path)

data = []
for f in sorted(glob.glob(f"{root}/*/diagnosis/diagnosis.json")):
    label = f.split("/")[-3]; c = cases.get(label)
    if c is None or c.split != "tuning": continue
    truth = {e if e == "action_delay" else f"{e}@{t}" for e, t, _ in c.effects}
    data.append(load(f, c.kind, truth, label))
data.append(load(os.path.join(emps_run, "diagnosis.json"), "real", {"coulomb_friction@axis"}, "EMPS"))

def replay(rule, verbose=False):
    g, t, L, stat, S = rule
    res = []
    for label, kind, truth, rounds, path in data:
        named = []
        for k, cands in enumerate(rounds):
            ok = [c for c in cands if c[1] <= 1 - g and (c[2][stat[0]] >= t if not isinstance(stat, tuple) or len(stat)==1 else
                  (c[2][stat[0]] >= t or c[2][stat[1]] >= t)) and (c[3] > L or c[1] <= S)]
            if not ok: break
            best = min(ok, key=lambda c: c[1])[0]
            named.append(best)
            if k >= len(path) or best != path[k]: break
        res.append((kind, set(named) == truth, len(set(named) - truth) > 0 and kind == "none", label, named))
        if verbose and set(named) != truth: print("  ", label, named)
    cnt = lambda k: sum(r[1] for r in res if r[0] == k)
    return cnt("single"), cnt("double"), sum(r[2] for r in res if r[0] == "none"), cnt("real"), sum(r[0]=="none" and r[1] for r in res)

print("cases", len(data), {k: sum(d[1] == k for d in data) for k in ("single", "double", "none", "real")})
best = []
stats = [("raw",), (0.1,), (1.0,), (10.0,), ("sign",), ("raw", 0.1), ("raw", 1.0)]
for rule in itertools.product([0.03, 0.05, 0.1, 0.2], [1.5, 2.0, 2.5, 3.0, 4.0], [0, 0.03, 0.1, 0.3], stats, [0, 0.1, 0.3, 0.5]):
    s, d, f, r, nn = replay(rule)
    best.append((f, -r, -(s + d), str(rule), s, d, r, nn))
best.sort()
for b in best[:25]: print("false_none", b[0], "single", b[4], "double", b[5], "emps", b[6], "none-correct", b[7], "rule", b[3])
if len(sys.argv) > 3:
    r = eval(sys.argv[3]); print(r, replay(r, verbose=True))
