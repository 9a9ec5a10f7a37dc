"""The sim-to-real loop, end to end: train, record on the target, diagnose, retrain; repeat.

    python scripts/loop.py config=configs/pendulum.yaml target=benchmarks/plants/pendulum_real.xml \\
        iterations=2 episodes=3 out=runs/loop

``target``: the "real" system, an MJCF stepped by native MuJoCo (``scripts/record.py``).
``run``: a trained run to start from (default: the config is trained first, ``out/nominal``).
``iterations``: record -> diagnose -> retrain rounds (``sim2real/tools/loop.py``), in ``out/iter_<k>``.
``episodes``: recorded episodes per iteration (the last is held out by the diagnosis).
``eval_episodes``: episodes on the target that score each policy at the end (``out/loop.json``).
``noise``: the target's position-sensor noise (m or rad). ``fallback.params=[..]
fallback.low=[..] fallback.high=[..]``: the box an iteration trains on when its diagnosis cannot be
used (inconclusive, or body masses re-fitted more than 10x off). Every other ``key=value`` (and
``config=``) is the training config's, as for ``scripts/train.py``; ``diagnose.<key>=value``
sets a diagnosis option.
"""
import json
import os
import sys

from sim2real.common import compile_cache
from sim2real.common.cli import main_guard


def main(argv):
    import dataclasses

    import numpy as np

    from sim2real.common import config as config_lib, output
    from sim2real.tools import loop
    from sim2real.tools.record import from_run
    from sim2real.training.driver import TrainConfig, train, validate

    mine, rest = config_lib.split(argv, loop.LoopConfig)
    diag_opts = [a.split(".", 1)[1] for a in rest if a.startswith("diagnose.")]
    base = config_lib.load(TrainConfig, [a for a in rest if not a.startswith("diagnose.")])
    validate(base)
    own = config_lib.load(loop.LoopConfig, mine)
    if own.fallback.params:  # checked now, not after the first training and diagnosis
        from sim2real.algos.base import DRSpace
        from sim2real.envs import make

        try:
            DRSpace(make(base.env, **dict(base.env_options)), own.fallback, key="fallback")
        except (ValueError, KeyError) as e:
            raise config_lib.ConfigError(f"fallback: {e}") from None
    if not os.path.exists(own.target):
        raise FileNotFoundError(f"target={own.target}: file not found")
    out = own.out
    output.create(out, "loop", inputs=[own.target], overwrite=own.overwrite)
    base = dataclasses.replace(base, progress=own.progress, overwrite=False, resume=False)
    runs = {}
    if own.run:
        runs["start"] = own.run
    else:
        runs["nominal"] = train(dataclasses.replace(base, name="nominal", out_dir=out))["run_dir"]
    steps = []
    run = next(iter(runs.values()))
    for k in range(1, own.iterations + 1):
        it = loop.iteration(run, base, own.target, os.path.join(out, f"iter_{k}"), own.episodes,
                            seed=own.seed + k, noise=own.noise, deterministic=own.deterministic,
                            diagnose_options=diag_opts, progress=own.progress, warm_start=own.warm_start,
                            fallback=own.fallback, until_end=own.until_end, warm_std=own.warm_std)
        d = it["diagnosis"]
        print(f"iteration {k}: recorded return {it['real_return']:.1f}; diagnosis: {d['answer']}"
              + "".join(f"; {s['effect']}" + (f"@{s['target']}" if s["target"] else "") + " "
                        + ", ".join(f"{n}={v:.4g}" for n, v in s["params"].items()) for s in d["selected"])
              + (f"; trained on the fallback box ({it['why']})" if it["trained_on"] == "fallback" else ""))
        steps.append(it)
        run = runs[f"iter_{k}"] = it["run"]
    scores = {}
    for name, r in runs.items():  # every policy on the target, the same initial states
        rets = [from_run(r, own.target, own.eval_episodes, seed=10_000 + own.seed, run_seed=s,
                         noise=own.noise)[0].ret for s in range(base.num_seeds)]
        scores[name] = {"run": r, "mean": float(np.mean(rets)), "per_seed": [float(np.mean(x)) for x in rets]}
        print(f"{name:>10s}: return on the target {scores[name]['mean']:.1f} over {own.eval_episodes} episodes"
              + (f" x {base.num_seeds} seeds" if base.num_seeds > 1 else ""))
    with open(os.path.join(out, "loop.json"), "w") as f:
        json.dump({"target": os.path.abspath(own.target), "iterations": steps, "scores": scores}, f, indent=2)
    print(f"wrote {os.path.join(out, 'loop.json')}")


HELP = ('sim2real.tools.loop:LoopConfig', 'sim2real.training.runs:TrainConfig')  # the typed configs whose keys ``-h`` lists


def run(argv=None):
    """Console entry point ``sim2real-loop`` (and ``python -m sim2real loop``)."""
    compile_cache.enable()  # compiled programs kept between runs (common/compile_cache.py says why)
    main_guard(main, sys.argv[1:] if argv is None else argv, doc=__doc__, configs=HELP)


if __name__ == "__main__":
    run()
