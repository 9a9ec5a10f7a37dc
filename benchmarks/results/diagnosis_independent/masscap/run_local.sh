#!/bin/bash
# the mass cap (a worktree WT with it, e.g. /tmp/wt) on the tuning lists' cases the device runs did
# not cover, one case at a time on this machine: bash run_local.sh WT OUT
WT=$1; OUT=$2
source $(dirname $0)/rest_sets.sh
export servo= pairs= timing=
cd $WT && export PYTHONPATH=$WT
for s in combos tuning pairs timing servo extra; do
  /work/main/.venv/bin/python benchmarks/diagnosis_independent.py split=$s only=${!s} jobs=1 out=$OUT/r \
    work=/tmp/cap_work tag=_masscap > $OUT/$s.log 2>&1
done
