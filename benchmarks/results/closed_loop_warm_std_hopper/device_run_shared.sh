#!/usr/bin/env bash
# The hopper's fine-tuned loop with the restart, every method starting from ONE nominal training
# (device_run.sh trained it again in every process: five GPU processes, each with its own nominal
# policies, and two loop seeds cut by the call's limit). Two calls on one NVIDIA H200, run from the
# repo root with run(carry=[".whlmin", ".hopper_nominal"]):
#   PHASE=1: trains the 3-seed nominal chain alone, scores it, then fine-tunes the oracle
#            (oracle_ft) and the wide box (udr_wide_ft) from it, two processes; the nominal run
#            folder comes back in $OUT/nominal.tgz (unpack it into .hopper_nominal/ for PHASE=2).
#   PHASE=2: the loop (diag_dr_1, fine-tuned) for seeds 0, 1, 2, one process each, from that folder.
#   PHASE=boxes, more, loop2: boxes.py's retraining on the GPU (below; its docstring says the order);
#   PHASE=simopt: SimOpt alone from .hopper_nominal's nominal.
# Settings as device_run.sh (closed_loop_until_end's fifth call with loop_warm_start and
# warm_std=0.6065): the real budget's 3 episodes logged past the fall, an 8-step delay line,
# the span box, the shared-lag candidate motor_lag_all.
set -u
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site ${WHL:-.whlmin}/*.whl || exit
if ! ls ${WHL:-.whlmin}/trimesh-*.whl > /dev/null 2>&1; then
  # no trimesh wheel carried (the working tree with it was over the device's 64 MiB): MJX imports
  # it at the top of mesh.py but uses it only for mesh geoms, which the hopper has none of
  mkdir -p /tmp/site/trimesh && printf 'class Trimesh:\n    def __init__(self, *a, **k):\n        raise ImportError("trimesh: a stand-in, not installed")\n' > /tmp/site/trimesh/__init__.py
fi
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
SETUP=${SETUP:-hopper}  # closed_loop.SETUPS' key: hopper_b is the held-out plant
COMMON="env=$SETUP seeds=3 total_steps=30000000 loop_warm_start=true record_until_end=true warm_std=0.6065"
# EXTRA_SET: more training settings (seed=1: other chains than seed 0's; boxes.py config_set=)
SET="config_set=env_options.max_delay=8;dr.diagnosis_box=span${EXTRA_SET:+;$EXTRA_SET}"
DIAG="diagnose_set=effects=[none,coulomb_friction,viscous_damping,joint_stiffness,sensor_offset,mass_offset,action_delay,motor_lag,actuator_saturation,backlash,motor_lag_all]"
DEV="device=NVIDIA H200 (one GPU)"
LIMIT=${LIMIT:-570}
T0=$(date +%s)
mkdir -p /tmp/res/logs
if [ "${PHASE:-1}" = 1 ]; then
  timeout $LIMIT python3 benchmarks/closed_loop.py $COMMON "$SET" methods=nominal out=/tmp/res/nominal \
    work=/tmp/cl_nom "$DEV" > /tmp/res/logs/nominal.txt 2>&1
  NOM=/tmp/cl_nom/$SETUP/nominal
  LEFT=$(( LIMIT - ($(date +%s) - T0) ))
  for m in oracle_ft udr_wide_ft; do
    timeout $LEFT python3 benchmarks/closed_loop.py $COMMON "$SET" methods=$m nominal=$NOM out=/tmp/res/$m \
      work=/tmp/cl_$m "$DEV" > /tmp/res/logs/$m.txt 2>&1 &
  done
  for s in ${SIMOPT:+0 1 2}; do  # SIMOPT=1: SimOpt from each seed's nominal recordings beside them
    timeout $LEFT python3 benchmarks/closed_loop.py $COMMON "$SET" methods=simopt only_seeds=$s nominal=$NOM \
      out=/tmp/res/simopt_s$s work=/tmp/cl_so$s "$DEV" > /tmp/res/logs/simopt_$s.txt 2>&1 &
  done
  wait
  # the policy and its config (what nominal= and a warm start read), not the checkpoints (over 16 MiB)
  tar czf $OUT/nominal.tgz --exclude=nominal/checkpoints -C /tmp/cl_nom/$SETUP nominal
elif [ "$PHASE" = boxes ]; then
  # the loop's retraining on two boxes around the same diagnoses (boxes.py part=diagnose, run on the
  # 2-core CPU from the nominal.tgz of PHASE=1, copied to .hopper_nominal/diag): six processes
  mkdir -p /tmp/res/boxes && cp -r .hopper_nominal/diag/* /tmp/res/boxes/
  for s in 0 1 2; do for b in ${BOXES:-centred span}; do
    timeout $LIMIT python3 benchmarks/results/closed_loop_warm_std_hopper/boxes.py part=retrain box=$b seed=$s \
      "config_set=${EXTRA_SET:-}" setup=$SETUP nominal=.hopper_nominal/nominal out=/tmp/res/boxes > /tmp/res/logs/retrain_${s}_$b.txt 2>&1 &
  done; done
  wait
  rm -rf /tmp/res/boxes/*/run/checkpoints /tmp/res/boxes/*_*/run/checkpoints
elif [ "$PHASE" = more ]; then
  # the first loop again on the centred box (PHASE=boxes kept no policy, and the second loop starts
  # from it) and SimOpt from each seed's nominal recordings: six processes, .hopper_nominal as above
  mkdir -p /tmp/res/two_loops && cp -r .hopper_nominal/diag/* /tmp/res/two_loops/
  for s in 0 1 2; do
    timeout $LIMIT python3 benchmarks/results/closed_loop_warm_std_hopper/boxes.py part=retrain box=centred seed=$s \
      "config_set=${EXTRA_SET:-}" setup=$SETUP nominal=.hopper_nominal/nominal out=/tmp/res/two_loops > /tmp/res/logs/retrain_$s.txt 2>&1 &
    timeout $LIMIT python3 benchmarks/closed_loop.py $COMMON "$SET" methods=simopt only_seeds=$s \
      nominal=.hopper_nominal/nominal out=/tmp/res/simopt_s$s work=/tmp/cl_so$s "$DEV" > /tmp/res/logs/simopt_$s.txt 2>&1 &
  done
  wait
  rm -rf /tmp/res/two_loops/*/run/checkpoints
elif [ "$PHASE" = simopt ]; then
  # SimOpt alone from each seed's nominal recordings (PHASE=more without the first loop again,
  # whose policies came back from PHASE=boxes): three processes, .hopper_nominal as above
  for s in 0 1 2; do
    timeout $LIMIT python3 benchmarks/closed_loop.py $COMMON "$SET" methods=simopt only_seeds=$s \
      nominal=.hopper_nominal/nominal out=/tmp/res/simopt_s$s work=/tmp/cl_so$s "$DEV" > /tmp/res/logs/simopt_$s.txt 2>&1 &
  done
  wait
elif [ "$PHASE" = loop2 ]; then
  # the second loop's retraining from the first's policies on the diagnoses of their recordings
  # (boxes.py part=diagnose iteration=2 on the 2-core CPU; .hopper_nominal/two_loops holds
  # seed<s>_centred/run and seed<s>_centred_diag2/diagnosis), and LSDR from scratch (3 seeds)
  cp -r .hopper_nominal/two_loops /tmp/res/two_loops
  for s in 0 1 2; do
    timeout $LIMIT python3 benchmarks/results/closed_loop_warm_std_hopper/boxes.py part=retrain iteration=2 \
      box=centred seed=$s "config_set=${EXTRA_SET:-}" setup=$SETUP nominal=.hopper_nominal/nominal out=/tmp/res/two_loops > /tmp/res/logs/retrain2_$s.txt 2>&1 &
  done
  timeout $LIMIT python3 benchmarks/closed_loop.py $COMMON "$SET" methods=lsdr out=/tmp/res/lsdr work=/tmp/cl_lsdr \
    "$DEV" > /tmp/res/logs/lsdr.txt 2>&1 &
  wait
  rm -rf /tmp/res/two_loops/*/run/checkpoints
else
  NOM=$PWD/.hopper_nominal/nominal
  [ -d /tmp/cl_nom/$SETUP/nominal ] && NOM=/tmp/cl_nom/$SETUP/nominal  # the same machine, still warm
  ls $NOM/policy.msgpack || exit 1
  for s in 0 1 2; do
    timeout $LIMIT python3 benchmarks/closed_loop.py $COMMON "$SET" "$DIAG" methods=diag_dr_1 only_seeds=$s \
      nominal=$NOM out=/tmp/res/s$s work=/tmp/cl_s$s "$DEV" > /tmp/res/logs/seed$s.txt 2>&1 &
  done
  wait
  for s in 0 1 2; do
    mkdir -p /tmp/res/s$s/diag
    cp /tmp/cl_s$s/$SETUP/loop_$s/iter_1/diagnosis/diagnosis.json /tmp/res/s$s/diag/ 2>/dev/null
    cp /tmp/cl_s$s/$SETUP/loop_$s/iter_1/recordings/record.json /tmp/res/s$s/diag/ 2>/dev/null
  done
fi
for f in /tmp/res/logs/*.txt; do echo "== $f"; grep -v "^WARNING\|^W0000\|^I0000" $f | grep -v "^$" | tail -6; done
echo "phase ${PHASE:-1}: $(( $(date +%s) - T0 )) s"; nvidia-smi --query-gpu=name --format=csv,noheader
tar czf $OUT/hopper_phase${PHASE:-1}.tgz -C /tmp/res .
