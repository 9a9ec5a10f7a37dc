#!/bin/bash
# The oracle check (benchmarks/diagnosis_ceiling.py) of the tuning lists' misses, on the device's
# CPUs: ``bash run_device.sh LIST...`` (everything packed in ceiling.tgz, the logs beside it), each list's cases from tuning_misses.txt (``list case``
# lines: every tuning-list case whose latest stored answer is wrong). Stops at SECONDS_LEFT.
D=benchmarks/results/diagnosis_independent/ceiling
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD/benchmarks:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
end=$((SECONDS + ${SECONDS_LEFT:-540}))
for l in "$@"; do
  grep "^$l " $D/${SETS:-tuning_misses.txt} | cut -d" " -f2 > /tmp/$l.txt
  left=$((end - SECONDS)); [ $left -lt 20 ] && break
  timeout $left python3 benchmarks/diagnosis_ceiling.py split=$l cases=/tmp/$l.txt jobs=${JOBS:-8} out=$OUT \
    work=/tmp/ow > $OUT/$l.log 2>&1
  echo "rc=$?" >> $OUT/$l.log
done
cd $OUT && tar czf ceiling.tgz *.log *.csv *.md && rm -f *.csv *.md && cd - >/dev/null
grep -c "^truth passes\|^tie\|^answer passes\|^not searched\|^error" $OUT/*.log
