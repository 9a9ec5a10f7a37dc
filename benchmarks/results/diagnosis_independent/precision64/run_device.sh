#!/bin/bash
# One device call (run(carry=[".whlmin"]): mujoco 4.0.0, mujoco-core 4.0.0, mujoco-mjx 3.17.0, glfw,
# pyopengl, trimesh wheels, cp312): LISTS="tuning pairs" SECONDS_LEFT=520 bash run_device.sh.
# Every case of the lists under the diagnosis' defaults (f32) and with precision=64 (f64), the two
# settings of a case next to each other, one case per CPU core (heldout_segments/run_device.py).
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl || exit
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
export SETTINGS='{"f32": {}, "f64": {"precision": 64}}'
python3 benchmarks/results/diagnosis_independent/heldout_segments/run_device.py $OUT ${SECONDS_LEFT:-520} $LISTS > $OUT/run.log 2>&1
grep -v "^WARNING\|^W0000\|^I0000" $OUT/run.log | tail -20; nproc; python3 -c "import jax, mujoco; print(jax.__version__, mujoco.__version__)"
cd $OUT && gzip -k *.jsonl && wc -l *.jsonl
