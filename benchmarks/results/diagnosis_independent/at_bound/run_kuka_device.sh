#!/usr/bin/env bash
# The two KUKA LWR4+ splits alone on the device's CPUs (run(carry=[".whlmin"])), which did not
# finish within 430 s beside the five other real recordings (run_real_device.sh);
# defaults, plots=false; each one's diagnosis.json (gzipped), report.md and log to $OUT/kuka.tgz.
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl || exit
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
S=sim2real/sysid/data/kuka_lwr4
R=/tmp/real
run() {  # name recordings heldout
  mkdir -p $R/$1
  timeout ${LIMIT:-500} python3 scripts/diagnose.py model=$S/kuka_lwr4.xml recordings="[$2]" heldout="[$3]" out=/tmp/diag_$1 \
    plots=false progress=false > $R/$1/log.txt 2>&1
  [ -f /tmp/diag_$1/diagnosis.json ] && gzip -c /tmp/diag_$1/diagnosis.json > $R/$1/diagnosis.json.gz && cp /tmp/diag_$1/report.md $R/$1/
}
run kuka_lwr4 $S/run1.csv,$S/run2.csv $S/run3.csv &
run kuka_lwr4_swapped $S/run3.csv $S/run1.csv &
wait
cd $R && tar czf $OUT/kuka.tgz * && for s in *; do echo "== $s"; grep -v "^W1\|^I0\|^W0\|WARNING" $s/log.txt | tail -14; done
