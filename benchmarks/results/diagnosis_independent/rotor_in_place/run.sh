# The tuning lists' 67 cases whose stored rows name a backlash (heldout_segments/), run again with
# SelectConfig.rotor on (a named band fitted again as its joint's rotor inertia; 2-core CPU,
# fifty-seventh session). OUT=/tmp/ri by default.
cd /work/main
OUT=${OUT:-/tmp/ri}
mkdir -p $OUT
run() { PYTHONPATH=. .venv/bin/python benchmarks/diagnosis_independent.py split=$1 only=$2 jobs=1 out=$OUT tag=_ri work=$OUT/work >> $OUT/log.txt 2>&1; }
run tuning 000_,022_,004_,026_,132_
run combos 6071_,6103_,6097_,6098_,6135_
run extra 1007_,1006_,1004_,1037_,1036_,1064_,1065_,1038_
run servo 3702_,3701_,3704_,3703_,3706_,3705_,3707_,3708_,3709_
run focus 3002_,3006_,3007_,3013_,3014_,3015_,3026_,3025_,3027_,3032_,3033_,3039_,3048_,3049_,3051_,3055_,3057_,3064_,3065_
run pairs 3500_,3501_,3502_,3503_,3504_,3505_,3507_,3506_,3509_,3510_,3511_,3512_,3513_,3514_,3515_,3522_,3523_,3529_,3525_,3530_,3531_
echo done >> $OUT/log.txt
