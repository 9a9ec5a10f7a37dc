#!/usr/bin/env bash
# The diagnosis on one NVIDIA H200 (JAX's default backend there: the GPU), on tuning cases with
# 8 s recordings, one case at a time, to set its time beside the 2-core CPU's. Run from the repo
# root with run(carry=[".whlhop"]); the wheels as device_run_shared.sh installs them.
#   WHL=.whlhop CASES=002_,004_ bash benchmarks/results/diagnosis_independent/gpu_h200/run.sh
set -u
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site ${WHL:-.whlhop}/*.whl || exit
if ! python3 -c "import trimesh" 2> /dev/null; then  # (MJX imports it for mesh geoms, which no case has)
  mkdir -p /tmp/site/trimesh && printf 'class Trimesh:\n    def __init__(self, *a, **k):\n        raise ImportError("trimesh: a stand-in")\n' > /tmp/site/trimesh/__init__.py
fi
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
python3 -c "import jax; print('JAX', jax.__version__, jax.devices())"
timeout ${LIMIT:-500} python3 benchmarks/diagnosis_independent.py split=tuning only=$CASES jobs=1 out=$OUT tag=_gpu work=/tmp/w \
  | grep -v "^W0000\|^I0000"
# every finished case's diagnosis.json (its ``seconds``), also when the limit cut the run short
for d in /tmp/w/*/diagnosis; do c=$(basename $(dirname $d)); mkdir -p $OUT/cases/$c; cp $d/diagnosis.json $OUT/cases/$c/ 2> /dev/null; done
nvidia-smi --query-gpu=name --format=csv,noheader
