#!/usr/bin/env bash
# The seven diagnoses of the bundled real recordings (EMPS, both DFKI, IBM and KUKA splits; as
# finer_ratio/run_real.sh) on the device's CPU cores, all at once (run(carry=[".whlmin"]));
# defaults, plots=false; each one's diagnosis.json (gzipped), report.md and log to $OUT/real.tgz.
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl || exit
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
S=sim2real/sysid/data
R=/tmp/real
run() {  # name model recordings heldout
  mkdir -p $R/$1
  timeout ${LIMIT:-500} python3 scripts/diagnose.py model=$2 recordings="[$3]" heldout="[$4]" out=/tmp/diag_$1 \
    plots=false progress=false > $R/$1/log.txt 2>&1
  gzip -c /tmp/diag_$1/diagnosis.json > $R/$1/diagnosis.json.gz && cp /tmp/diag_$1/report.md $R/$1/
}
run emps $S/emps/emps_nominal.xml $S/emps/DATA_EMPS.mat "" &
run dfki_pendulum $S/dfki_pendulum/pendulum.xml $S/dfki_pendulum/energy_shaping.csv $S/dfki_pendulum/sac.csv &
run dfki_pendulum_swapped $S/dfki_pendulum/pendulum.xml $S/dfki_pendulum/sac.csv $S/dfki_pendulum/energy_shaping.csv &
run ibm_double_pendulum $S/ibm_double_pendulum/double_pendulum.xml $S/ibm_double_pendulum/run0.csv,$S/ibm_double_pendulum/run1.csv $S/ibm_double_pendulum/run2.csv &
run ibm_double_pendulum_swapped $S/ibm_double_pendulum/double_pendulum.xml $S/ibm_double_pendulum/run1.csv,$S/ibm_double_pendulum/run2.csv $S/ibm_double_pendulum/run0.csv &
run kuka_lwr4 $S/kuka_lwr4/kuka_lwr4.xml $S/kuka_lwr4/run1.csv,$S/kuka_lwr4/run2.csv $S/kuka_lwr4/run3.csv &
run kuka_lwr4_swapped $S/kuka_lwr4/kuka_lwr4.xml $S/kuka_lwr4/run3.csv $S/kuka_lwr4/run1.csv &
wait
cd $R && tar czf $OUT/real.tgz * && python3 - <<'PY'
import gzip, json, os
for s in sorted(os.listdir(".")):
    p = os.path.join(s, "diagnosis.json.gz")
    if not os.path.exists(p):
        print(s, "no diagnosis:", open(os.path.join(s, "log.txt")).read()[-300:]); continue
    d = json.load(gzip.open(p))
    print(s, d["answer"], d["seconds"], "s", round(d["fit"]["before"], 4), "->", round(d["fit"]["after"], 4))
    for r in d["selected"]:
        print("   ", r["effect"], r["target"], {k: round(v, 4) for k, v in r["params"].items()}, "STAND-IN" if "stand_in" in r else "")
PY
