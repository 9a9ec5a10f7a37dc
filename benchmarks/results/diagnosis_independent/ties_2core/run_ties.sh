#!/bin/bash
# the tie-dropping paired test on every tuning-list case where some validation segment was a tie
cd /tmp/wt_tie && source sets.sh
export PYTHONPATH=/tmp/wt_tie
for s in timing tuning pairs servo beside focus extra combos; do
  /work/main/.venv/bin/python benchmarks/diagnosis_independent.py split=$s only=${!s} jobs=1 out=/tmp/tie_out tag=_tie work=/tmp/tie_work > /tmp/tie_out_$s.log 2>&1
done
