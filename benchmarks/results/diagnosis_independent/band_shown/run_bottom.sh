#!/bin/bash
# tuning.md step 69: every tuning-list case where a passing backlash's width ended at the bottom of
# its range in a stored run (the only ones the check, as kept, can change), with band_shown on
export combos=6002_,6025_,6027_,6036_,6050_,6051_,6132_,6134_,6135_
export pairs=3523_,3535_
export timing=3904_,3914_,3924_,3926_
export tuning=006_,034_,078_,124_
export extra=1001_,1028_,1046_,1062_,1069_,1126_
export focus=3009_,3011_,3016_,3017_,3018_,3019_,3028_,3037_,3054_,3063_
for s in combos focus extra pairs timing tuning; do
  python3 benchmarks/diagnosis_independent.py split=$s only=${!s} jobs=${JOBS:-8} out=$OUT/r work=/tmp/bb \
    tag=_band_bottom > $OUT/$s.log 2>&1 &
  [ "$s" = focus ] && wait   # two lists at a time
done
wait
grep -h "^OK\|^--" $OUT/*.log
