#!/bin/bash
# The start-velocity prior at a command's kink (kink_error) against the code before it, both on this
# machine's CPUs: the tuning lists' cases it touches (sets.txt: a nonzero bound at some segment start,
# affected.jsonl) and the floating-base tuning list (diagnosis_floating.py list=tuning). Before the call,
# in the repo root: git show HEAD~N:sim2real/sysid/trajectory.py > .old_trajectory.py (and shooting.py);
# then run(carry=[".whlmin"]) with VARIANTS="new old", SECONDS_LEFT and SETS: call 1 FLOATING=1 SETS=sets_1.txt,
# call 2 SETS=sets_2.txt (both made from affected_broad.jsonl, for the broad variant README.md describes;
# call 2 ran the pairs list before 3528 was found touched, so 3528 was not run).
D=benchmarks/results/diagnosis_independent/kink_prior
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
end=$((SECONDS + ${SECONDS_LEFT:-560}))
cp sim2real/sysid/trajectory.py /tmp/new_trajectory.py; cp sim2real/sysid/shooting.py /tmp/new_shooting.py
for v in ${VARIANTS:-new old}; do
  if [ $v = old ]; then cp .old_trajectory.py sim2real/sysid/trajectory.py; cp .old_shooting.py sim2real/sysid/shooting.py; fi
  left=$((end - SECONDS)); [ $left -lt 20 ] && break
  [ -n "$FLOATING" ] && timeout $left python3 benchmarks/diagnosis_floating.py list=tuning jobs=${JOBS:-16} out=$OUT/f_$v \
    work=/tmp/fw_$v > $OUT/floating_$v.log 2>&1
  for pair in $(cat $D/${SETS:-sets.txt}); do
    l=${pair%%:*}; o=${pair#*:}
    left=$((end - SECONDS)); [ $left -lt 20 ] && break
    timeout $left python3 benchmarks/diagnosis_independent.py split=$l only=$o jobs=${JOBS:-16} out=/tmp/r_$v \
      work=/tmp/ow_$v tag=_kink > $OUT/${v}_$l.log 2>&1
  done
  cp /tmp/new_trajectory.py sim2real/sysid/trajectory.py; cp /tmp/new_shooting.py sim2real/sysid/shooting.py
done
python3 $D/collect.py
grep -c "^--" $OUT/*.log
