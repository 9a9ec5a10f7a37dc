#!/usr/bin/env bash
# The hopper's fine-tuned loop with the restart (warm_std=0.6065, exp of the network's init_log_std,
# as on the CPU tasks), on one NVIDIA H200: the setting of closed_loop_until_end's fifth call
# (recordings logged past the fall, an 8-step delay line, the span box, the shared-lag candidate)
# with the loop fine-tuned (loop_warm_start=true) instead of trained from scratch. Five processes
# on the one GPU: one per seed for the loop (each trains the nominal chain again: GPU runs are not
# bit-reproducible, so each process's nominal policies differ), one for the fine-tuned oracle and
# one for the wide box fine-tuned (udr_wide_ft), each from its own process's nominal policies.
# Run from the repo root with .whlmin carried: bash benchmarks/results/closed_loop_warm_std_hopper/device_run.sh
set -u
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl || exit
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
COMMON="env=hopper seeds=3 total_steps=30000000 loop_warm_start=true record_until_end=true warm_std=0.6065"
SET="config_set=env_options.max_delay=8;dr.diagnosis_box=span"
DIAG="diagnose_set=effects=[none,coulomb_friction,viscous_damping,joint_stiffness,sensor_offset,mass_offset,action_delay,motor_lag,actuator_saturation,backlash,motor_lag_all]"
DEV="device=NVIDIA H200 (one GPU, five processes)"
LIMIT=${LIMIT:-560}
mkdir -p /tmp/res/logs
for s in 0 1 2; do
  timeout $LIMIT python3 benchmarks/closed_loop.py $COMMON "$SET" "$DIAG" methods=nominal,diag_dr_1 only_seeds=$s \
    out=/tmp/res/s$s work=/tmp/cl_s$s "$DEV" > /tmp/res/logs/seed$s.txt 2>&1 &
done
for m in oracle_ft udr_wide_ft; do
  timeout $LIMIT python3 benchmarks/closed_loop.py $COMMON "$SET" methods=$m out=/tmp/res/$m work=/tmp/cl_$m "$DEV" \
    > /tmp/res/logs/$m.txt 2>&1 &
done
wait
for s in 0 1 2; do
  mkdir -p /tmp/res/s$s/diag
  cp /tmp/cl_s$s/hopper/loop_$s/iter_1/diagnosis/diagnosis.json /tmp/res/s$s/diag/ 2>/dev/null
  cp /tmp/cl_s$s/hopper/loop_$s/iter_1/recordings/record.json /tmp/res/s$s/diag/ 2>/dev/null
done
for f in /tmp/res/logs/*.txt; do echo "== $f"; grep -v "^WARNING\|^W0000\|^I0000" $f | grep -v "^$" | tail -6; done
nvidia-smi --query-gpu=name --format=csv,noheader
tar czf $OUT/hopper_device.tgz -C /tmp/res .
