#!/bin/bash
# tuning.md step 76, on this 2-core machine from the working tree: bash run_local.sh LIST... (each
# list's cases from sets.txt: sets.py, every tuning-list case whose stored diagnosis had nothing pass
# on the nominal model, or a pair joined together, or with no stored diagnosis)
D=benchmarks/results/diagnosis_independent/pair_train
for l in "$@"; do
  o=$(tr " " "\n" < $D/sets.txt | grep "^$l:" | cut -d: -f2)
  .venv/bin/python benchmarks/diagnosis_independent.py split=$l only=$o jobs=1 out=/tmp/pt/r work=/tmp/pt/w tag=_pt > $D/$l.log 2>&1
done
