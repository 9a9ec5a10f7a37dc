"""One table from pendulum_device.sh's seven processes (each wrote its own <name>/pendulum/ folder):
the nominal rows once (every process trained the same 5-seed chain and scored it alike), the
loop's rows and diagnoses of each seed from its own process, the baselines from theirs. Writes
through closed_loop.write, so the summary and plot are the benchmark's own.

    python benchmarks/results/closed_loop_warm_std_span/merge_device.py /tmp/pdev benchmarks/results/closed_loop_warm_std_span
"""
import csv
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))
from benchmarks import closed_loop as cl  # noqa: E402

src, out = sys.argv[1], sys.argv[2]
rows, diagnoses, seconds = [], {}, {}
for name in ["loop_s0", "loop_s1", "loop_s2", "loop_s3", "loop_s4", "blind_ft", "oracle_ft"]:
    d = os.path.join(src, name, "pendulum")
    with open(os.path.join(d, "results.csv")) as f:
        for r in csv.DictReader(f):
            if r["method"] == "nominal" and name != "loop_s0":
                continue
            rows.append({"method": r["method"], "seed": int(r["seed"]), "return": float(r["return"])})
    with open(os.path.join(d, "diagnoses.json")) as f:
        diagnoses.update(json.load(f))
    with open(os.path.join(d, "seconds.json")) as f:
        for k, v in json.load(f).items():  # per process; the loop's summed over its processes
            seconds[k] = seconds.get(k, 0.0) + v if k == "diag_dr" else max(seconds.get(k, 0.0), v)
rows.sort(key=lambda r: (cl.METHODS.index(r["method"]), r["seed"]))
args = cl.Settings(env="pendulum", seeds=5, out=out, loop_warm_start=True, warm_std=0.6065,
                   config_set="dr.diagnosis_box=span",
                   device="device CPU (NVIDIA H200 host, 16 cores; 2 cores per process, taskset)")
cl.write(args, cl.SETUPS["pendulum"], rows, diagnoses, seconds)
