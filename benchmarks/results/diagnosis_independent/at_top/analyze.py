"""Where candidate fits end at an edge of their search range (``run_ranges.py`` output): counts by
whether ``select._at_edge`` widens that edge, whether the candidate is a true effect, passed its
round and was named; the passing ones listed. ``python analyze.py extra_2core``."""
import collections
import gzip
import json
import os
import sys
rng = {}
for l in gzip.open(os.path.join(sys.argv[1], "ranges.jsonl.gz"), "rt"):
    d = json.loads(l); rng.setdefault(d["case"], d["ranges"])
WIDENED = {"motor_lag", "action_delay", "backlash", "mass_offset"}
stats = collections.Counter(); rows = []
for l in gzip.open(os.path.join(sys.argv[1], "base.jsonl.gz"), "rt"):
    d = json.loads(l); r = rng.get(d["case"], {})
    truth = set(d["truth"]); named = set(d.get("named") or [])
    for k, rnd in enumerate(d.get("rounds") or []):
        for c in rnd:
            if not c.get("params"): continue
            lab = c["effect"] if c["effect"] == "action_delay" else f"{c['effect']}@{c['target']}"
            if lab not in r: continue
            lo, hi = r[lab]; v = list(c["params"].values())[0]
            top = v >= hi - 0.02 * abs(hi); bot = lo != 0 and v <= lo + 0.02 * abs(lo)
            if not (top or bot): continue
            key = ("widened" if c["effect"] in WIDENED or (c["effect"] == "actuator_saturation" and bot) else "not widened",
                   "true" if lab in truth else "false", "passed" if c.get("passed") else "failed",
                   "named" if lab in named else "not named")
            stats[key] += 1
            rows.append((d["case"], k, lab, "top" if top else "bottom", round(v, 5), [round(lo, 5), round(hi, 5)], key[1:], d.get("correct")))
print(len(rng), "cases with ranges")
for k, v in sorted(stats.items()): print(k, v)
for r in rows:
    if r[6][1] == "passed": print(r)
