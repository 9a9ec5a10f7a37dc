"""What the held-out walk and the delay/lag ranking need from each case of a run (read from the
work folders, so a list cut short by the device's time limit still counts its finished cases):
one JSON line per case. ``python extract.py WORK_FOLDER... > rows.jsonl``"""
import glob
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", ".."))
import diagnosis_independent as di  # noqa: E402

for work in sys.argv[1:]:
    for folder in sorted(glob.glob(os.path.join(work, "*"))):
        dj, tj = os.path.join(folder, "diagnosis", "diagnosis.json"), os.path.join(folder, "truth.json")
        if not (os.path.exists(dj) and os.path.exists(tj)):
            continue
        d, desc = json.load(open(dj)), json.load(open(tj))
        truth = sorted(di._key(e, t) for e, t, *_ in desc["effects"])
        rounds = [[{k: c.get(k) for k in ("effect", "target", "screen_score", "passed", "objective",
                                           "validation_ratio", "t", "params")}
                   | ({"validation": sum(c["validation_segments"])} if "validation_segments" in c else {})
                   for c in r["candidates"]] for r in d.get("rounds", [])]
        print(json.dumps({"case": desc["case"], "split": desc["split"], "kind": desc["kind"], "truth": truth,
                          "named": di.named_keys(d), "answer": d.get("answer"),
                          "param_errors": di._param_errors(desc, d), "seconds": d.get("seconds"),
                          "before": d["fit"]["before"], "after": d["fit"]["after"], "steps": d["steps"],
                          "energy_named": (d.get("energy") or {}).get("named"), "rounds": rounds}))
