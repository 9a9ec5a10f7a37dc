# The tuning lists' 24 voice-coil cases (the only benchmark system whose model declares a joint
# spring, 300 N/m) run with joint_stiffness searched on a declared spring (either sign; 2-core CPU,
# fifty-seventh session). OUT=/tmp/ds by default; BASE=1 runs the code before (git stash first).
cd /work/main
OUT=${OUT:-/tmp/ds}
mkdir -p $OUT
run() { PYTHONPATH=. .venv/bin/python benchmarks/diagnosis_independent.py split=$1 only=voice_coil jobs=1 out=$OUT tag=_ds work=$OUT/work >> $OUT/log.txt 2>&1; }
for s in tuning beside combos extra timing focus pairs; do run $s; done
echo done >> $OUT/log.txt
