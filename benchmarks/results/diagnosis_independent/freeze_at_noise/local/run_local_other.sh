cd /work/main
.venv/bin/python benchmarks/diagnosis_independent.py split=beside only=3824_,3825_,3829_ jobs=1 out=/tmp/an/lr tag=_other work=/tmp/w > /tmp/an/local_other_beside.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=combos only=6001_,6022_,6024_,6030_,6047_,6052_,6056_,6063_,6065_,6066_,6067_,6068_,6069_,6071_,6078_,6082_,6099_,6105_,6108_,6124_ jobs=1 out=/tmp/an/lr tag=_other work=/tmp/w > /tmp/an/local_other_combos.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=extra only=1005_,1014_,1017_,1043_,1055_,1063_,1084_,1125_,1127_ jobs=1 out=/tmp/an/lr tag=_other work=/tmp/w > /tmp/an/local_other_extra.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=focus only=3012_,3023_,3034_,3035_,3036_,3038_,3040_,3041_,3044_,3045_,3050_,3052_,3053_,3056_,3058_,3059_,3065_ jobs=1 out=/tmp/an/lr tag=_other work=/tmp/w > /tmp/an/local_other_focus.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=pairs only=3506_,3508_,3517_,3518_,3519_,3521_,3524_,3526_,3527_,3528_,3532_,3533_,3534_ jobs=1 out=/tmp/an/lr tag=_other work=/tmp/w > /tmp/an/local_other_pairs.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=servo only=3700_,3702_ jobs=1 out=/tmp/an/lr tag=_other work=/tmp/w > /tmp/an/local_other_servo.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=timing only=3900_,3901_,3902_,3913_,3915_,3916_,3918_,3920_,3931_ jobs=1 out=/tmp/an/lr tag=_other work=/tmp/w > /tmp/an/local_other_timing.log 2>&1
.venv/bin/python benchmarks/diagnosis_independent.py split=tuning only=050_ jobs=1 out=/tmp/an/lr tag=_other work=/tmp/w > /tmp/an/local_other_tuning.log 2>&1
