#!/bin/bash
# tuning.md step 74 on the KUKA LWR4+ (its diagnoses had saturation fits end at the bottom of
# their ranges), both splits as masscap/real/ ran them, on this 2-core machine
cd "$(dirname "$0")/../../../.." || exit 1
K=sim2real/sysid/data/kuka_lwr4
for s in "kuka_lwr4 run1.csv,$K/run2.csv run3.csv" "kuka_lwr4_swapped run3.csv run1.csv"; do
  set -- $s
  .venv/bin/python scripts/diagnose.py model=$K/kuka_lwr4.xml recordings="[$K/$2]" heldout="[$K/$3]" \
    out=/tmp/satreal/$1 plots=false progress=false overwrite=true > /tmp/satreal_$1.log 2>&1
  mkdir -p benchmarks/results/diagnosis_independent/sat_widen/real/$1
  cp /tmp/satreal/$1/diagnosis.json /tmp/satreal/$1/report.md benchmarks/results/diagnosis_independent/sat_widen/real/$1/
done
