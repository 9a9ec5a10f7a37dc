#!/bin/bash
# One device call: CASES=... SECONDS_LEFT=... bash run_device.sh (run(carry=[".whlmin"])).
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl || exit
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
here=benchmarks/results/diagnosis_independent/start_clip
python3 $here/run_oob.py $OUT ${SECONDS_LEFT:-420} > $OUT/run.log 2>&1
grep -v "^WARNING\|^W0000\|^I0000\|^W1203" $OUT/run.log | tail -5; wc -l $OUT/*.jsonl $OUT/oob.txt; cut -d' ' -f1 $OUT/oob.txt | sort | uniq -c
