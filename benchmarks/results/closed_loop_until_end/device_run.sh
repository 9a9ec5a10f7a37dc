#!/usr/bin/env bash
# The hopper's loop with the real budget's 3 episodes logged on past the fall (record_until_end),
# on a 2xH200 host: one process per seed (each trains its own nominal chain: GPU runs are not
# bit-reproducible) and, unless NOBASE=1, one for the baselines that need no nominal policy.
# Run from the repo root on the device with the wheels of .whlmin installed; results land in $OUT.
#   first call:  bash device_run.sh
#   second call: METHODS=nominal,simopt,diag_dr_1 NOBASE=1 EXTRA='config_set=env_options.max_delay=8' bash device_run.sh
#   third call:  WARM=false EXTRA='config_set=env_options.max_delay=8' bash device_run.sh
#                (the loop trains from scratch; EXTRA reaches the baselines too)
#   fourth call: WARM=false EXTRA='config_set=env_options.max_delay=8' \
#                DIAG='effects=[none,coulomb_friction,viscous_damping,joint_stiffness,sensor_offset,mass_offset,action_delay,motor_lag,actuator_saturation,backlash,motor_lag_all]' \
#                bash device_run.sh   (the loop's diagnosis may also name one lag shared by every motor)
#   fifth call:  as the fourth, with EXTRA='config_set=env_options.max_delay=8;dr.diagnosis_box=span'
#                (the loop's box reaches back to the env's own values: dr.diagnosis_box=span)
#   sixth call:  as the fifth, with ';seed=1' added to EXTRA's config_set (three new chains)
#   seventh call: as the fifth, with ';seed=2' (three more)
set -u
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_MEM_FRACTION=0.4
COMMON="env=hopper seeds=3 total_steps=30000000 loop_warm_start=${WARM:-true} record_until_end=true"
METHODS=${METHODS:-nominal,diag_dr_1}
EXTRA=${EXTRA:-}
DIAG=${DIAG:-}
LIMIT=${LIMIT:-540}
mkdir -p $OUT/logs
for s in 0 1 2; do
  CUDA_VISIBLE_DEVICES=$((s % 2)) timeout $LIMIT python benchmarks/closed_loop.py $COMMON methods=$METHODS only_seeds=$s \
    out=$OUT/s$s work=/tmp/cl_s$s "device=NVIDIA H200 (2xH200 host, one process per seed)" $EXTRA ${DIAG:+"diagnose_set=$DIAG"} > $OUT/logs/seed$s.txt 2>&1 &
done
if [ "${NOBASE:-0}" != 1 ]; then
  CUDA_VISIBLE_DEVICES=1 timeout $LIMIT python benchmarks/closed_loop.py $COMMON methods=udr_wide,oracle \
    out=$OUT/base work=/tmp/cl_base "device=NVIDIA H200 (2xH200 host)" $EXTRA > $OUT/logs/base.txt 2>&1 &
fi
wait
# the diagnoses themselves (diagnosis.json, the recordings' record.json) beside the tables
for s in 0 1 2; do
  mkdir -p $OUT/s$s/diag
  cp /tmp/cl_s$s/hopper/loop_$s/iter_1/diagnosis/diagnosis.json $OUT/s$s/diag/ 2>/dev/null
  cp /tmp/cl_s$s/hopper/loop_$s/iter_1/recordings/record.json $OUT/s$s/diag/ 2>/dev/null
done
cd $OUT && tar czf results.tgz s* base logs 2>/dev/null; tar czf results.tgz s* logs $( [ -d base ] && echo base ) && ls -la
tail -n 12 $OUT/logs/*.txt
