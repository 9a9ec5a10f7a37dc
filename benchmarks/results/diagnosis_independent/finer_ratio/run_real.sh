#!/bin/bash
# tuning.md step 81 on the bundled real recordings: the seven diagnoses of masscap/real/ (EMPS, both
# DFKI, IBM and KUKA splits) on the current code, on this 2-core machine; each one's diagnosis.json
# and report.md into real/<name>/. A finer-step check with a ratio in (0.5, 0.65] is the only way
# step 81 can move one of them (`python check_real.py` lists every finer check and the answers).
cd "$(dirname "$0")/../../../.." || exit 1
S=sim2real/sysid/data
run() {  # name model recordings heldout
  .venv/bin/python scripts/diagnose.py model=$2 recordings="[$3]" heldout="[$4]" \
    out=/tmp/finer_real/$1 plots=false progress=false overwrite=true > /tmp/finer_real_$1.log 2>&1
  mkdir -p benchmarks/results/diagnosis_independent/finer_ratio/real/$1
  cp /tmp/finer_real/$1/diagnosis.json /tmp/finer_real/$1/report.md benchmarks/results/diagnosis_independent/finer_ratio/real/$1/
}
run emps $S/emps/emps_nominal.xml $S/emps/DATA_EMPS.mat ""
run dfki_pendulum $S/dfki_pendulum/pendulum.xml $S/dfki_pendulum/energy_shaping.csv $S/dfki_pendulum/sac.csv
run dfki_pendulum_swapped $S/dfki_pendulum/pendulum.xml $S/dfki_pendulum/sac.csv $S/dfki_pendulum/energy_shaping.csv
run ibm_double_pendulum $S/ibm_double_pendulum/double_pendulum.xml $S/ibm_double_pendulum/run0.csv,$S/ibm_double_pendulum/run1.csv $S/ibm_double_pendulum/run2.csv
run ibm_double_pendulum_swapped $S/ibm_double_pendulum/double_pendulum.xml $S/ibm_double_pendulum/run1.csv,$S/ibm_double_pendulum/run2.csv $S/ibm_double_pendulum/run0.csv
run kuka_lwr4 $S/kuka_lwr4/kuka_lwr4.xml $S/kuka_lwr4/run1.csv,$S/kuka_lwr4/run2.csv $S/kuka_lwr4/run3.csv
run kuka_lwr4_swapped $S/kuka_lwr4/kuka_lwr4.xml $S/kuka_lwr4/run3.csv $S/kuka_lwr4/run1.csv
