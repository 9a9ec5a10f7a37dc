#!/usr/bin/env bash
# PPO seed-spread ablation on the GPU (issue: PPO that every seed can trust).
# Each variant: ${SEEDS:-5} vmapped seeds of configs/hopper.yaml (+ overrides), STEPS env steps per
# seed, every seed's deterministic policy evaluated on 32 episodes (benchmarks/hopper_ppo.py).
# Variants run one after another: as concurrent processes sharing one H100 they were no faster in
# total (three 8-seed x 100M hopper runs had not finished after 560 s; in turn, about 3 x 180 s).
#   bash benchmarks/ppo_ablation.sh OUTDIR STEPS "name|overrides" ...
set -u
out=$1; steps=$2; shift 2
mkdir -p "$out"
one() {
  local name=${1%%|*} ov=${1#*|}
  echo "=== $name: $ov"
  python3 benchmarks/hopper_ppo.py num_seeds=${SEEDS:-5} total_steps=$steps eval_episodes=32 name=$name \
      out_dir="$out/runs" tensorboard=false progress=false overwrite=true $ov 2>&1 | grep -v "^WARNING" | tail -3
  # the run folder lives under OUTDIR so a run cut off by a time limit still leaves its metrics.csv
  cp "$out/runs/$name/summary.json" "$out/$name.json" 2>/dev/null
  cp "$out/runs/$name/metrics.csv" "$out/${name}_metrics.csv" 2>/dev/null
}
for v in "$@"; do one "$v"; done
