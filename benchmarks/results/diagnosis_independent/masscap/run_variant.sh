#!/bin/bash
# a variant of sim2real/ (PATCH: a diff of it, applied to a copy in /tmp/variant), run on parts of tuning lists:
# PATCH=benchmarks/results/diagnosis_independent/masscap/masscap.diff bash run_variant.sh TAG "list:only list:only ..."  (only: comma-separated label parts, or ALL)
TAG=$1; shift
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
rm -rf /tmp/variant && mkdir -p /tmp/variant && cp -r sim2real /tmp/variant/ && patch -s -p0 -d /tmp/variant < $PATCH || exit 1
export PYTHONPATH=/tmp/site:/tmp/variant:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
python3 -c "import sim2real; print(sim2real.__file__)"
end=$((SECONDS + ${SECONDS_LEFT:-540}))
for lo in $1; do
  l=${lo%%:*}; o=${lo#*:}; [ "$o" = ALL ] && o=""
  left=$((end - SECONDS)); [ $left -lt 20 ] && break
  timeout $left python3 benchmarks/diagnosis_independent.py split=$l only=$o jobs=${JOBS:-8} out=$OUT/r work=/tmp/ow \
    tag=_$TAG > $OUT/$l.log 2>&1
  echo "rc=$?" >> $OUT/$l.log
done
cd /tmp/ow && tar czf $OUT/cases.tgz $(ls -d */ | sed 's#/$##' | while read c; do ls $c/truth.json $c/diagnosis/diagnosis.json $c/diagnosis/report.md 2>/dev/null; done)
grep -c "^OK\|^--" $OUT/*.log
