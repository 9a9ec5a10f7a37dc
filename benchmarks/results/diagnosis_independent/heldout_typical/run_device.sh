#!/bin/bash
# Tuning lists on the device's CPUs (16 cores, one case per core) with the held-out walk's typical
# segment (DiagnoseConfig.heldout_typical); each case's steps and rounds to $OUT/<split>.jsonl
# (extract.py), from which the pooled-only walk's answers are rebuilt. SPLITS="..." picks the lists,
# ONLY="a,b" the cases whose labels hold one of those texts.
# run(carry=[".whlmin"]).
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whlmin/*.whl
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 JAX_PLATFORMS=cpu
here=benchmarks/results/diagnosis_independent/heldout_typical
end=$((SECONDS + ${SECONDS_LEFT:-570}))
for s in $SPLITS; do
  left=$((end - SECONDS)); [ $left -lt 30 ] && break
  timeout $left python3 benchmarks/diagnosis_independent.py split=$s jobs=16 out=/tmp/r work=/tmp/w_$s tag=_typ ${ONLY:+only=$ONLY} \
    > $OUT/$s.log 2>&1
  python3 $here/extract.py /tmp/w_$s > $OUT/$s.jsonl
  echo "$s: $(wc -l < $OUT/$s.jsonl) cases, $(grep -c '^OK' $OUT/$s.log) OK"
done
