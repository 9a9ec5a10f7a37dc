"""Read a run of ``run_device.sh`` (``device/*.jsonl.gz``) two ways (``tuning.md`` steps 83-84):

1. The held-out walk: each case's answer rebuilt with the pooled NRMSE only (``heldout_walk``
   with ``heldout_typical=False``) against the run's (``heldout_typical=True``), and every step a
   typical segment kept that the pooled error would not.
2. A delay against a lag: every round where both passed and one of the two is the truth, the one
   ranked first by the sum of the fitted and validation errors (``Selector.best`` before step 83)
   and by their product.

``python analyse.py [device/*.jsonl.gz]``"""
import glob
import gzip
import json
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
from sim2real.sysid.diagnose import DiagnoseConfig, heldout_walk  # noqa: E402

files = sys.argv[1:] or sorted(glob.glob(os.path.join(os.path.dirname(__file__), "device", "*.jsonl.gz")))
rows = [json.loads(line) for f in files for line in gzip.open(f, "rt")]
pooled = DiagnoseConfig(model="m", recordings=("a",), heldout_typical=False)
print(f"{len(rows)} cases, {sum(set(r['named']) == set(r['truth']) for r in rows)} right with the typical segment")
print("\n1. steps the typical segment kept and the pooled error would not:")
for r in rows:
    st = r["steps"]
    keep = max(k for k, s in enumerate(st) if s["kept"])
    if r["energy_named"] is None:
        old = heldout_walk([s["heldout_nrmse"] for s in st], r["before"], None, [s["joins_next"] for s in st], pooled)
        if old != keep:
            added = set(st[keep]["model"].split(" + ")) - set(st[old]["model"].split(" + "))
            print(f"  {r['case']}: {' + '.join(sorted(added))} ({'true' if added <= set(r['truth']) else 'FALSE'}); "
                  f"pooled ratio {st[keep]['heldout_nrmse'] / st[keep - 1]['heldout_nrmse']:.3f}, typical "
                  f"{st[keep]['heldout_typical_ratio']:.3f}")
print("\n2. rounds where a delay and a lag both passed, one of them true, and the sum or the product missed it:")
tally = {"sum": 0, "product": 0, "rounds": 0}
for r in rows:
    truth = set(r["truth"])
    for k, rnd in enumerate(r["rounds"]):
        passed = {c["effect"] + ("@" + c["target"] if c["target"] else ""): c for c in rnd if c.get("passed")}
        d = passed.get("action_delay")
        for name, lag in passed.items():
            if d is None or not name.startswith("motor_lag") or ("action_delay" in truth) == (name in truth):
                continue
            true = "delay" if "action_delay" in truth else "lag"
            by_sum = "delay" if d["objective"] + d["validation"] < lag["objective"] + lag["validation"] else "lag"
            by_product = ("delay" if math.log(d["objective"] * d["validation"]) < math.log(lag["objective"] * lag["validation"])
                          else "lag")
            tally["rounds"] += 1
            tally["sum"] += by_sum == true
            tally["product"] += by_product == true
            if by_sum != true or by_product != true:
                print(f"  {r['case']} round {k}: true {true}, sum {by_sum}, product {by_product}; delay/lag "
                      f"fitted {d['objective'] / lag['objective']:.3f}, validation {d['validation'] / lag['validation']:.3f}")
print(f"  right of {tally['rounds']} delay-lag pairs: sum {tally['sum']}, product {tally['product']}")
