#!/bin/bash
# tuning.md step 74 (a saturation that ends at the bottom of its range fitted again from starts
# down to 1/64 of it), on this 2-core machine from the working tree: the beside list whole, and
# every other tuning-list case whose stored diagnosis (masscap/ local runs, timing_restart/
# device runs) had a saturation fit end at that bottom.
cd "$(dirname "$0")/../../../.." || exit 1
O=benchmarks/results/diagnosis_independent/sat_widen
run() { .venv/bin/python benchmarks/diagnosis_independent.py split=$1 only=$2 jobs=2 out=/tmp/satout work=/tmp/sat_work tag=_sat > $O/$1.log 2>&1; }
run beside ""
run combos 6012_,6013_,6017_,6098_,6099_,6124_,6125_,6128_
run extra 1129_,1130_
# then the extra list's saturation cases, and the tuning and combos lists' cases without a stored
# diagnosis (a false saturation at the bottom of its range can move there too); run2 LOG SPLIT ONLY
run2() { .venv/bin/python benchmarks/diagnosis_independent.py split=$2 only=$3 jobs=2 out=/tmp/satout work=/tmp/sat_work tag=_sat$1 > $O/$1.log 2>&1; }
run2 extra_sat extra 1018_,1019_,1026_,1027_,1034_,1035_,1062_,1063_,1078_,1079_
run2 tuning tuning 006_,008_,028_,032_,042_,088_,090_,092_,094_,096_,098_,100_,102_,104_,106_,108_,110_,112_,114_,116_,118_,124_,128_,130_,134_
run2 combos_rest combos 6004_,6005_,6014_,6015_,6026_,6027_,6038_,6039_,6050_,6051_,6064_,6065_,6076_,6077_,6088_,6089_,6122_,6123_,6134_,6135_
