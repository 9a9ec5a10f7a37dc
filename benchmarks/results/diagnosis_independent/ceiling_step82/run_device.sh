#!/bin/bash
# Tuning lists on the device's CPUs at one commit (16 cores, one case per core), then the oracle check
# (diagnosis_ceiling.py) of each list's misses: where the selection's own test says the truth would win
# (fixable) and where the data tie. SPLITS="timing beside" (call 1), SPLITS=combos (call 2).
# run(carry=[".whlmin"]); $OUT gets <split>.log, <split>_summary.md, <split>_cases.csv, <split>_ceiling.{md,csv,log}.
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
end=$((SECONDS + ${SECONDS_LEFT:-570}))
for s in $SPLITS; do
  timeout $((end - SECONDS)) python3 benchmarks/diagnosis_independent.py split=$s jobs=16 out=/tmp/r work=/tmp/w_$s tag=_step82 \
    > $OUT/$s.log 2>&1
  cp /tmp/r/${s}_step82/summary.md $OUT/${s}_summary.md; cp /tmp/r/${s}_step82/cases.csv $OUT/${s}_cases.csv
  grep -c "^OK" $OUT/$s.log; grep "^--" $OUT/$s.log
done
for s in $SPLITS; do
  left=$((end - SECONDS)); [ $left -lt 40 ] && break
  timeout $left python3 benchmarks/diagnosis_ceiling.py split=$s results=/tmp/r/${s}_step82 jobs=16 work=/tmp/wc_$s \
    out=/tmp/c tag=_step82 > $OUT/${s}_ceiling.log 2>&1
  cp /tmp/c/${s}_step82.md $OUT/${s}_ceiling.md; cp /tmp/c/${s}_step82.csv $OUT/${s}_ceiling.csv
  head -8 $OUT/${s}_ceiling.md
done
