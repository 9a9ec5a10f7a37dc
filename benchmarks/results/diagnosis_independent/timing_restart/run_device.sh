#!/bin/bash
# tuning.md step 73 (a candidate on top of a delay or lag also fitted from half of it), run from the
# working tree on the device's CPUs: ``bash run_device.sh LIST...``, each list's cases from
# sets.txt (sets.py: a delay or lag in the truth or the latest stored answer). Stops waiting at
# SECONDS_LEFT and packs each case's diagnosis. SETS=extra_rest.txt: the extra list's cases of neither kind
# that the mass limit's runs (masscap/) did not cover.
D=benchmarks/results/diagnosis_independent/timing_restart
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
end=$((SECONDS + ${SECONDS_LEFT:-540}))
for l in "$@"; do
  o=$(tr " " "\n" < $D/${SETS:-sets.txt} | grep "^$l:" | cut -d: -f2)
  left=$((end - SECONDS)); [ $left -lt 20 ] && break
  timeout $left python3 benchmarks/diagnosis_independent.py split=$l only=$o jobs=${JOBS:-8} out=$OUT/r work=/tmp/ow \
    tag=_restart$TAG > $OUT/$l.log 2>&1
  echo "rc=$?" >> $OUT/$l.log
done
cd /tmp/ow && tar czf $OUT/cases.tgz $(ls -d */ | sed 's#/$##' | while read c; do ls $c/truth.json $c/diagnosis/diagnosis.json $c/diagnosis/report.md 2>/dev/null; done)
grep -c "^OK\|^--" $OUT/*.log
