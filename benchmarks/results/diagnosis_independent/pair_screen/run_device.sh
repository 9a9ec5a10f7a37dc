#!/bin/bash
# tuning.md step 80, the device's CPUs: the rest of the extra list's cases of sets.txt (sets3.txt),
# then the combos cases whose answers moved without a screened pair, with the step off
# (``diagnose.pair_screen=0``), to tell the step's moves from the platform's.
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
D=benchmarks/results/diagnosis_independent/pair_screen
python3 benchmarks/diagnosis_independent.py split=extra only=$(cut -d: -f2 $D/sets3.txt) jobs=8 out=$OUT/r work=/tmp/ow3 tag=_ps3 > $OUT/extra.log 2>&1 &
python3 benchmarks/diagnosis_independent.py split=combos only=6002_,6023_,6024_,6097_,6098_,6099_,6101_,6102_,6103_,6121_ jobs=5 out=$OUT/r work=/tmp/ow0 tag=_ps0 diagnose.pair_screen=0 > $OUT/combos_off.log 2>&1
wait
grep -c "^OK\|^--" $OUT/*.log
