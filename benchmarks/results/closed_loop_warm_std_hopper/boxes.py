"""The hopper's fine-tuned loop on two boxes around the same diagnoses (span and centred), with
the loop's own pieces (``loop.diagnose``, ``loop.retrain``) split over two machines: the
diagnoses on the 2-core CPU, the retraining on one NVIDIA H200 (device time is short).

    # on the GPU (device_run_shared.sh PHASE=1): nominal, oracle_ft and udr_wide_ft; nominal.tgz back
    python benchmarks/results/closed_loop_warm_std_hopper/boxes.py part=diagnose nominal=DIR out=DIR
    python benchmarks/results/closed_loop_warm_std_hopper/boxes.py part=retrain nominal=DIR out=DIR box=centred seed=0
    python benchmarks/results/closed_loop_warm_std_hopper/boxes.py part=summary out=DIR
    # several summaries' chains as one table (each out's seed s as chain 10 k + s)
    python benchmarks/results/closed_loop_warm_std_hopper/boxes.py part=pooled outs=DIR,DIR
    # the second loop (closed_loop.py's diag_dr_2): record loop 1's policy, diagnose, retrain from it
    python .../boxes.py part=diagnose iteration=2 box=centred nominal=DIR out=DIR
    python .../boxes.py part=retrain iteration=2 box=centred nominal=DIR out=DIR seed=0

Settings as ``closed_loop.py``'s hopper calls of ``device_run_shared.sh`` (the same config, the
real budget's 3 episodes of each seed's nominal policy logged past the fall, the shared-lag
candidate, fine-tuned with ``warm_std=0.6065``; 64 evaluation episodes on the real plant).
``part=retrain`` reads ``out/seed<s>/diagnosis`` and writes ``out/seed<s>_<box>/`` with
``score.json``. ``iteration=2`` is closed_loop's second loop: ``part=diagnose`` records the
first loop's policy (``out/seed<s>_<box>/run``, initial states ``200 + s``) into
``out/seed<s>_<box>_diag2/``, ``part=retrain`` fine-tunes that policy on this diagnosis into
``out/seed<s>_<box>_2/``. ``config_set``: more training settings (``seed=1`` for other chains);
``setup=hopper_b``: the held-out plant (``closed_loop.SETUPS``).
A diagnosis' ``model`` is the env's MJCF on the machine that diagnosed: it is pointed at this
machine's copy of the same file (``check_same_model`` still compares them).
"""
import dataclasses
import json
import os
import sys

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(ROOT, "benchmarks"))

import closed_loop  # noqa: E402

SET = ["env_options.max_delay=8", "num_seeds=1"]
DIAG = ["effects=[none,coulomb_friction,viscous_damping,joint_stiffness,sensor_offset,mass_offset,action_delay,"
        "motor_lag,actuator_saturation,backlash,motor_lag_all]"]


@dataclasses.dataclass
class Args:
    part: str = "diagnose"
    nominal: str = ""
    out: str = ""
    box: str = "centred"
    seed: int = 0
    seeds: str = "0,1,2"
    outs: str = ""  # part=pooled: the summaries' folders, comma-separated
    iteration: int = 1
    config_set: str = ""  # more training settings, ';'-separated (device_run_shared.sh's EXTRA_SET)
    total_steps: int = 30_000_000  # (less only to try the script; the nominal check then refuses)
    episodes: int = 64
    setup: str = "hopper"  # closed_loop.SETUPS' key: the plant (hopper_b: the held-out one)


def main(a: Args):
    from sim2real.common import config as config_lib
    from sim2real.envs.registry import env_class
    from sim2real.tools import loop
    from sim2real.training.driver import TrainConfig

    if a.part == "summary":
        return summary(a.out)
    if a.part == "pooled":
        return pooled([x for x in a.outs.split(",") if x])
    hoppers = [k for k, v in closed_loop.SETUPS.items() if v["config"].endswith("hopper.yaml")]
    if a.setup not in hoppers:
        raise SystemExit(f"setup={a.setup}: one of {', '.join(hoppers)}")
    setup = closed_loop.SETUPS[a.setup]
    plant = os.path.join(ROOT, setup["plant"])
    extra = [x for x in a.config_set.split(";") if x.strip()]
    base = config_lib.load(TrainConfig, [f"config={os.path.join(ROOT, setup['config'])}"] + SET + extra
                           + [f"dr.diagnosis_box={a.box}", f"total_steps={a.total_steps}"])
    if a.total_steps == Args.total_steps:
        closed_loop._earlier_nominal(a.nominal, base, 3)
    if a.iteration not in (1, 2):
        raise SystemExit(f"iteration={a.iteration}: 1 or 2")
    if a.part == "diagnose":
        for s in [int(x) for x in a.seeds.split(",")]:
            policy, run_seed, where = _source(a, s)
            _, what, d = loop.diagnose(policy, base, plant, os.path.join(a.out, where), 3, seed=100 * a.iteration + s,
                                       run_seed=run_seed, noise=1e-3, deterministic=True, diagnose_options=DIAG,
                                       until_end=True)
            print(f"seed {s}: recorded return {what['mean_return']:.1f}; "
                  + "; ".join(f"{x['effect']} {x['params']}" for x in d["selected"]), flush=True)
        return
    s = a.seed
    policy, run_seed, where = _source(a, s)
    out = os.path.join(a.out, f"seed{s}_{a.box}" + ("_2" if a.iteration == 2 else ""))
    diag = os.path.join(out, "diagnosis")
    os.makedirs(diag)
    d = json.load(open(os.path.join(a.out, where, "diagnosis", "diagnosis.json")))
    d["model"] = loop.env_model_path(env_class(base.env))
    json.dump(d, open(os.path.join(diag, "diagnosis.json"), "w"))
    res, dr, why = loop.retrain(policy, dataclasses.replace(base, seed=s), out, d, run_seed=run_seed, warm_start=True,
                                fallback=closed_loop._wide(setup), warm_std=0.6065)
    score = closed_loop._scores(res["run_dir"], plant, a.episodes, 1)[0]
    json.dump({"seed": s, "box": a.box, "iteration": a.iteration, "return": score,
               "trained_on": "diagnosis" if dr.from_diagnosis else "fallback",
               "why": why or "", "dr": yaml.safe_load(open(os.path.join(res["run_dir"], "config.yaml")))["dr"]},
              open(os.path.join(out, "score.json"), "w"), indent=1)
    print(f"seed {s} box {a.box} iteration {a.iteration}: {score:.1f}", flush=True)


def _source(a: Args, s: int) -> tuple[str, int, str]:
    """Iteration ``a.iteration``'s recorded policy for seed ``s`` (its run folder and the seed in
    it) and the folder under ``a.out`` its recordings and diagnosis go to."""
    if a.iteration == 1:
        return a.nominal, s, f"seed{s}"
    return os.path.join(a.out, f"seed{s}_{a.box}", "run"), 0, f"seed{s}_{a.box}_diag2"


def summary(out: str) -> None:
    """``out/results.csv`` and ``out/summary.md``: every column per seed (closed_loop.py's columns
    from their ``results.csv``, copied into ``out/<method>/``), the loop's against each baseline paired
    by seed (the same nominal chain)."""
    import glob

    import numpy as np

    rows = {}
    for m in ("nominal", "oracle_ft", "udr_wide_ft", "simopt", "lsdr"):
        if not os.path.exists(os.path.join(out, m, "results.csv")):
            continue
        for r in closed_loop.read_results(os.path.join(out, m)):
            rows.setdefault(r["method"], {})[r["seed"]] = r["return"]
    for f in sorted(glob.glob(os.path.join(out, "seed*_*", "score.json"))):
        r = json.load(open(f))
        name = f"loop_{r['box']}" + ("_2" if r.get("iteration", 1) == 2 else "")
        rows.setdefault(name, {})[r["seed"]] = r["return"]
    seeds = sorted(rows["nominal"])
    with open(os.path.join(out, "results.csv"), "w") as f:
        f.write("method,seed,return\n" + "".join(f"{m},{s},{v!r}\n" for m, by in rows.items() for s, v in sorted(by.items())))
    lines = ["| method | " + " | ".join(f"seed {s}" for s in seeds) + " | mean |", "|---" * (len(seeds) + 2) + "|"]
    for m, by in rows.items():
        lines.append(f"| {m} | " + " | ".join(f"{by[s]:.1f}" for s in seeds) + f" | {np.mean(list(by.values())):.1f} |")
    loops = tuple(m for m in ("loop_span", "loop_centred", "loop_centred_2") if m in rows)
    lines += closed_loop.paired_lines([{"method": m, "seed": s, "return": v} for m, by in rows.items()
                                       for s, v in by.items()], loops=loops)
    oracle = np.mean(list(rows["oracle_ft"].values()))
    lines += [""] + [f"{m}: {np.mean(list(rows[m].values())) / oracle:.0%} of the fine-tuned oracle's mean return"
                     for m in rows if m not in ("nominal", "oracle_ft")]
    open(os.path.join(out, "summary.md"), "w").write("\n".join(lines) + "\n")
    print("\n".join(lines))


def chains(outs: list[str]) -> list[dict]:
    """The rows of several ``part=summary`` folders (other nominal trainings) as one list of chains:
    seed ``s`` of the ``k``-th folder is chain ``10 k + s``."""
    return [dict(r, seed=10 * k + r["seed"]) for k, out in enumerate(outs) for r in closed_loop.read_results(out)]


def pooled(outs: list[str]) -> None:
    """The chains of several ``part=summary`` folders (``chains``) as one table: each method's mean
    over the chains it ran on, and the loop against the others paired by chain. Printed only."""
    import numpy as np

    rows = chains(outs)
    methods = list(dict.fromkeys(r["method"] for r in rows))
    oracle = {r["seed"]: r["return"] for r in rows if r["method"] == "oracle_ft"}
    print(f"{len(outs)} tables: " + ", ".join(outs))
    head = "method | chains | mean | min | max | of the fine-tuned oracle's mean on those chains"
    print(f"\n| {head} |\n" + "|---" * 6 + "|")
    for m in methods:
        by = {r["seed"]: r["return"] for r in rows if r["method"] == m}
        v = list(by.values())
        print(f"| {m} | {len(v)} | {np.mean(v):.1f} | {min(v):.1f} | {max(v):.1f} "
              f"| {np.mean(v) / np.mean([oracle[c] for c in by]):.0%} |")
    print("\n".join(closed_loop.paired_lines(rows, loops=tuple(m for m in methods if m.startswith("loop_")))))


if __name__ == "__main__":
    from sim2real.common import config as config_lib

    main(config_lib.load(Args, sys.argv[1:]))
