"""Per-seed training trace of a run's metrics.csv: mean reward per step, PPO's approx. KL and the
policy's entropy at chosen updates.   python training.py RUN_DIR [seeds]"""
import csv
import sys

rows = list(csv.DictReader(open(f"{sys.argv[1]}/metrics.csv")))
seeds = sys.argv[2].split(",") if len(sys.argv) > 2 else sorted({r["seed"] for r in rows})
for s in seeds:
    rs = [r for r in rows if r["seed"] == s]
    at = [0, 1, 2, 5, 10, 20, 50, 100, 200, 400, 700, len(rs) - 1]
    print(sys.argv[1].rstrip("/").split("/")[-1], "seed", s, " ".join(
        f"{rs[i]['update']}:{float(rs[i]['mean_reward']):.3f}/kl{float(rs[i]['approx_kl']):.3f}/H{float(rs[i]['entropy']):.2f}"
        for i in at if i < len(rs)))
