#!/usr/bin/env bash
# The pendulum's loop with the span box and the restart (dr.diagnosis_box=span, warm_std=0.6065),
# one and two loops, beside its fine-tuned baselines, on the device's CPU cores (JAX_PLATFORMS=cpu):
# seven processes, each pinned to 2 cores (taskset; 2 cores is the machine the other closed-loop
# tables ran on), each training the same 5-seed nominal chain: the loop one seed per process,
# udr_blind_ft and oracle_ft one process each. Run from the repo root with .whlmin carried:
#   bash benchmarks/results/closed_loop_warm_std_span/pendulum_device.sh
set -u
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl || exit
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
COMMON="env=pendulum seeds=5 loop_warm_start=true warm_std=0.6065 config_set=dr.diagnosis_box=span"
DEV="device=device CPU (2 cores of a 16-core host per process)"
LIMIT=${LIMIT:-560}
mkdir -p /tmp/res/logs
run() {  # name cores methods [extra]
  taskset -c $2 timeout $LIMIT python3 benchmarks/closed_loop.py $COMMON methods=$3 ${4:-} out=/tmp/res/$1 \
    work=/tmp/cl_$1 "$DEV" > /tmp/res/logs/$1.txt 2>&1 &
}
for s in 0 1 2 3 4; do run loop_s$s $((2*s)),$((2*s+1)) nominal,diag_dr_1,diag_dr_2 only_seeds=$s; done
run blind_ft 10,11 udr_blind_ft
run oracle_ft 12,13 oracle_ft
wait
nproc; python3 -c "import jax, mujoco; print(jax.__version__, mujoco.__version__)"
for f in /tmp/res/logs/*.txt; do echo "== $f"; grep -v "^WARNING\|^W0000\|^I0000" $f | tail -8; done
tar czf $OUT/pendulum_device.tgz -C /tmp/res .
