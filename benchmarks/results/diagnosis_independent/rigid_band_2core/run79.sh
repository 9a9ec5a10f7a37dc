cd /work/main
run() { .venv/bin/python benchmarks/diagnosis_independent.py split=$1 only=$2 jobs=1 out=/tmp/s33/r79 tag=_$1 work=/tmp/s33/w79 > /tmp/s33/log79_$1.txt 2>&1; }
run tuning 060_
run beside 3839_
run combos 6009_,6056_,6057_,6094_,6023_,6091_,6111_
run extra 1122_,1123_
run timing 3921_
run servo ""
run pairs ""
echo done > /tmp/s33/batch79.done
