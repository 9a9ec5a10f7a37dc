#!/bin/bash
# the invdyn fix (sensing hooks per sample) against the code before it, on the tuning lists' cases
# whose stored answer holds a sensor offset; both on this machine's CPUs. Before the call, in the repo root:
# git show 89b4f00:sim2real/sysid/invdyn.py > .old_invdyn.py; then run(carry=[".whlmin"]) this script
D=benchmarks/results/diagnosis_independent/invdyn_sensing
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
end=$((SECONDS + ${SECONDS_LEFT:-560}))
cp sim2real/sysid/invdyn.py /tmp/new_invdyn.py
for v in new old; do
  [ $v = old ] && cp .old_invdyn.py sim2real/sysid/invdyn.py
  for pair in $(cat $D/sets.txt); do
    l=${pair%%:*}; o=${pair#*:}
    left=$((end - SECONDS)); [ $left -lt 20 ] && break
    timeout $left python3 benchmarks/diagnosis_independent.py split=$l only=$o jobs=8 out=/tmp/r_$v work=/tmp/ow_$v \
      tag=_inv > /tmp/log_${v}_$l.log 2>&1
  done
done
cp /tmp/new_invdyn.py sim2real/sysid/invdyn.py
python3 - <<'PY'
import json, glob, os
out = {}
for v in ("new", "old"):
    for p in glob.glob(f"/tmp/ow_{v}/*/diagnosis/diagnosis.json"):
        d = json.load(open(p)); c = p.split("/")[3]
        out.setdefault(c, {})[v] = {"answer": d["answer"], "named": [s["effect"] + "@" + str(s.get("target")) for s in d["selected"]],
                                    "after": d["fit"]["after"], "energy": json.dumps(d.get("energy"), sort_keys=True)[:20000]}
json.dump(out, open(os.environ["OUT"] + "/inv.json", "w"))
PY
cd /tmp && tar czf $OUT/logs.tgz log_*.log
grep -c "^--" /tmp/log_*.log
