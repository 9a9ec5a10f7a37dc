cd /work/main
.venv/bin/python benchmarks/diagnosis_independent.py split=combos only=6002_,6019_,6023_,6060_,6062_,6096_,6097_,6102_,6103_,6107_,6110_,6115_,6119_,6127_,6136_ jobs=1 out=/tmp/an/lr tag=_tp work=/tmp/w > /tmp/an/local_tp_combos.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=extra only=1039_,1064_ jobs=1 out=/tmp/an/lr tag=_tp work=/tmp/w > /tmp/an/local_tp_extra.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=beside only=3847_ jobs=1 out=/tmp/an/lr tag=_tp work=/tmp/w > /tmp/an/local_tp_beside.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=focus only=3003_,3020_,3022_,3024_,3054_ jobs=1 out=/tmp/an/lr tag=_tp work=/tmp/w > /tmp/an/local_tp_focus.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=tuning only=128_ jobs=1 out=/tmp/an/lr tag=_tp work=/tmp/w > /tmp/an/local_tp_tuning.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=pairs only=3504_,3514_,3516_,3520_,3535_ jobs=1 out=/tmp/an/lr tag=_tp work=/tmp/w > /tmp/an/local_tp_pairs.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=timing only=3917_ jobs=1 out=/tmp/an/lr tag=_tp work=/tmp/w > /tmp/an/local_tp_timing.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=combos only=6061_,6064_,6070_,6072_,6073_,6074_,6075_,6076_,6077_,6079_,6080_,6081_,6083_,6084_,6085_,6086_,6087_,6088_,6089_,6090_,6091_,6092_,6093_,6094_,6095_,6098_,6100_,6101_,6104_,6106_,6109_,6111_,6112_,6113_,6114_,6116_,6117_,6118_,6120_,6121_,6122_,6123_,6125_,6126_,6128_,6129_,6130_,6131_,6132_,6133_,6134_,6135_,6137_,6138_,6139_ jobs=1 out=/tmp/an/lr tag=_rest work=/tmp/w > /tmp/an/local_rest_combos.log 2>&1
