#!/bin/bash
# finer_ratio step (tuning.md step 81): the tuning lists' cases from $SETS (sets.txt: every case whose step-80
# diagnosis is not stored, affected.txt: the stored ones a finer check with a ratio in (0.5, 0.8] could move), on the
# device's CPUs: ``SETS=sets.txt EXTRA=diagnose.finer_ratio=0.65 TAG=_x bash run_device.sh LIST...``; stops waiting at
# SECONDS_LEFT and packs each case's diagnosis.
D=benchmarks/results/diagnosis_independent/finer_ratio
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
end=$((SECONDS + ${SECONDS_LEFT:-540}))
for l in "$@"; do
  o=$(tr " " "\n" < $D/${SETS:-sets.txt} | grep "^$l:" | cut -d: -f2)
  left=$((end - SECONDS)); [ $left -lt 20 ] && break
  timeout $left python3 benchmarks/diagnosis_independent.py split=$l only=$o jobs=${JOBS:-8} out=$OUT/r work=/tmp/ow \
    tag=$TAG $EXTRA > $OUT/$l.log 2>&1
  echo "rc=$?" >> $OUT/$l.log
done
cd /tmp/ow && tar czf $OUT/cases.tgz $(ls -d */ | sed 's#/$##' | while read c; do ls $c/truth.json $c/diagnosis/diagnosis.json $c/diagnosis/report.md 2>/dev/null; done)
grep -c "^OK\|^--" $OUT/*.log
