#!/bin/bash
# tuning.md step 71 (a Coulomb friction's onset no sharper than a physics step resolves): one
# tuning list per device call, ``bash run_device.sh LIST``; the per-case diagnoses are tarred into
# $OUT before the call's time limit (SECONDS_LEFT: when to stop waiting and pack what is done)
LIST=$1
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
timeout ${SECONDS_LEFT:-540} python3 benchmarks/diagnosis_independent.py split=$LIST jobs=${JOBS:-8} out=$OUT/r work=/tmp/ow \
  tag=_onset > $OUT/$LIST.log 2>&1
echo "rc=$?" >> $OUT/$LIST.log
cd /tmp/ow && tar czf $OUT/${LIST}_cases.tgz $(ls -d */ | sed 's#/$##' | while read c; do ls $c/truth.json $c/diagnosis/diagnosis.json $c/diagnosis/report.md 2>/dev/null; done)
tail -3 $OUT/$LIST.log
