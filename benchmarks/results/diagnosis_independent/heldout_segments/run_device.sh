#!/bin/bash
# One device call: LISTS="combos" SECONDS_LEFT=545 bash run_device.sh (run(carry=[".whlmin"]); make_whlmin.sh builds .whlmin).
# The tuning lists on the host's CPU cores (run_device.py), each list's lines to $OUT/<setting>.jsonl.
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl || exit
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
here=benchmarks/results/diagnosis_independent/heldout_segments
python3 $here/run_device.py $OUT ${SECONDS_LEFT:-545} $LISTS > $OUT/run.log 2>&1
grep -v "^WARNING\|^W0000\|^I0000" $OUT/run.log | tail -20; nproc; python3 -c "import jax, mujoco; print(jax.__version__, mujoco.__version__)"
