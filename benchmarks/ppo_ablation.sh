#!/usr/bin/env bash
# PPO seed-spread ablation on the GPU (issue: PPO that every seed can trust).
# Each variant: ${SEEDS:-5} vmapped seeds of configs/hopper.yaml (+ overrides), STEPS env steps per
# seed, every seed's deterministic policy evaluated on 32 episodes (benchmarks/hopper_ppo.py).
# With PARALLEL=1 the variants run as concurrent processes sharing the GPU (each gets a quarter of
# its memory): their throughput figures are then shared too and not comparable with a lone run.
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
if [ "${PARALLEL:-0}" = 1 ]; then
  export XLA_PYTHON_CLIENT_MEM_FRACTION=0.22
  for v in "$@"; do one "$v" > "$out/${v%%|*}.log" 2>&1 & done
  wait
  cat "$out"/*.log
else
  for v in "$@"; do one "$v"; done
fi
