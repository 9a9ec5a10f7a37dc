# The tuning lists' cases where a delay was named on a model with several actuators (stored rows), run
# again with SelectConfig.shared_lag on (2-core CPU, fifty-sixth session): ~13 min.
cd /work/main
run() { PYTHONPATH=. .venv/bin/python benchmarks/diagnosis_independent.py split=$1 only=$2 jobs=1 out=/tmp/sl tag=_sl work=/tmp/sl_work >> /tmp/sl/log.txt 2>&1; }
run tuning 062_arm3,126_arm2
run combos 6022_,6028_,6029_,6034_,6035_,6040_,6041_,6061_
run timing 3906_,3907_,3908_,3909_,3910_,3911_
run pd 7006_,7007_,7008_,7012_,7013_,7014_
run extra 1054_,1039_
run focus 3020_
echo done >> /tmp/sl/log.txt
