#!/usr/bin/env bash
# tuning.md step 59: the extra list with and without `motor_lag_all` among the searched effects,
# side by side on one lent host's CPUs (JOBS per run: half its cores) (answers move between hosts, so both runs on the same one).
# Run from the repo root on the device with the wheels of .whlmin installed; results land in $OUT.
set -u
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
EFF='diagnose.effects=[none,coulomb_friction,viscous_damping,joint_stiffness,sensor_offset,mass_offset,action_delay,motor_lag,actuator_saturation,backlash,motor_lag_all]'
cd benchmarks
timeout ${LIMIT:-540} python diagnosis_independent.py split=extra jobs=${JOBS:-15} work=/tmp/sc_a out=$OUT tag=_default > $OUT/extra_default.log 2>&1 &
timeout ${LIMIT:-540} python diagnosis_independent.py split=extra jobs=${JOBS:-15} work=/tmp/sc_b out=$OUT tag=_shared_lag "$EFF" > $OUT/extra_shared_lag.log 2>&1 &
wait
cd $OUT && tar czf results.tgz extra_* && ls -la && tail -n 30 extra_default.log extra_shared_lag.log | grep -v "^OK"
