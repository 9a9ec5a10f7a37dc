#!/bin/bash
# The third call: the narrow rule (windows of 7-11 samples) on every case it touches (sets.txt), the code
# before it on those of the lists the first two calls did not run (sets_old3.txt), every list at once (two
# copies of the tree, one per variant), then the floating-base tuning list with the narrow rule.
# run(carry=[".whlmin"]) after .old_trajectory.py/.old_shooting.py are made.
D=benchmarks/results/diagnosis_independent/kink_prior
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
end=$((SECONDS + ${SECONDS_LEFT:-560}))
for v in new old; do mkdir -p /tmp/$v && cp -r sim2real benchmarks /tmp/$v/; done
cp .old_trajectory.py /tmp/old/sim2real/sysid/trajectory.py; cp .old_shooting.py /tmp/old/sim2real/sysid/shooting.py
launch() {  # variant sets-file
  for pair in $(cat $D/$2); do
    l=${pair%%:*}; o=${pair#*:}; n=$(echo $o | tr "," "\n" | wc -l)
    (cd /tmp/$1 && PYTHONPATH=/tmp/site:/tmp/$1 timeout $((end - SECONDS)) python3 benchmarks/diagnosis_independent.py \
      split=$l only=$o jobs=$n out=/tmp/r_$1_$l work=/tmp/ow_$1 tag=_kink > $OUT/${1}_$l.log 2>&1) &
  done
}
launch new sets.txt
launch old sets_old3.txt
wait
left=$((end - SECONDS))
[ $left -gt 60 ] && (cd /tmp/new && PYTHONPATH=/tmp/site:/tmp/new timeout $left python3 benchmarks/diagnosis_floating.py \
  list=tuning jobs=16 out=$OUT/f_new work=/tmp/fw_new > $OUT/floating_new.log 2>&1)
python3 $D/collect.py
grep -c "^--" $OUT/*.log
