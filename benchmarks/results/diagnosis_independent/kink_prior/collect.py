"""Gather every diagnosis the device runs wrote (/tmp/ow_<variant>, /tmp/fw_<variant>) into $OUT/answers.json."""
import glob
import json
import os

out = {}
for v in ("new", "old"):
    for p in glob.glob(f"/tmp/ow_{v}/*/diagnosis/diagnosis.json") + glob.glob(f"/tmp/fw_{v}/*/diagnosis/diagnosis.json"):
        d = json.load(open(p))
        c = p.split("/")[3]
        out.setdefault(c, {})[v] = {"answer": d["answer"], "after": d["fit"]["after"], "before": d["fit"]["before"],
                                    "selected": [{k: s[k] for k in ("effect", "target", "params")} for s in d["selected"]]}
json.dump(out, open(os.environ["OUT"] + "/answers.json", "w"), indent=0)
