#!/bin/bash
# The PD-loop timing list (split=pd, sysid_cases.pd_cases(), 36 cases) on the device's CPUs (16 cores,
# one case per core), then the oracle check (diagnosis_ceiling.py) of its misses.
# run(carry=[".whlmin"]); prints the logs; $OUT gets cases.csv, summary.md, the check's table and every
# case's diagnosis.json.
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
end=$((SECONDS + ${SECONDS_LEFT:-560}))
timeout $((end - SECONDS)) python3 benchmarks/diagnosis_independent.py split=pd jobs=16 out=$OUT/r work=/tmp/pw tag=${TAG:-_device} \
  > $OUT/pd.log 2>&1
grep "^OK\|^--" $OUT/pd.log
left=$((end - SECONDS))
[ $left -gt 60 ] && timeout $left python3 benchmarks/diagnosis_ceiling.py split=pd results=$OUT/r/pd${TAG:-_device} jobs=16 \
  work=/tmp/pw_ceiling out=$OUT/ceiling > $OUT/ceiling.log 2>&1
tail -30 $OUT/ceiling.log
mkdir -p $OUT/diag && for d in /tmp/pw/*/diagnosis/diagnosis.json; do c=$(basename $(dirname $(dirname $d))); cp $d $OUT/diag/$c.json; done
