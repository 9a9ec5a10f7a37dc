"""Evaluate a run's policy over a grid of physics values and draw a return heat map.

    python scripts/evaluate.py run=runs/pendulum_udr x=mass:pole=0.3:2.0:9 y=gain:motor=1:3:9 episodes=4

``x`` (and optionally ``y``) are ``name=low:high:count`` or ``name=v1,v2,...``; other parameters
stay at the run's fixed values. Writes ``<run>/eval/returns.csv`` and ``returns.png`` (the
training DR box is outlined). All seeds of the run are evaluated and averaged.
"""
import os
import sys

from sim2real.cli import main_guard


def main(argv):
    import jax
    import numpy as np

    from sim2real import config as config_lib
    from sim2real.evaluate import episodes, grid, parse_axis
    from sim2real.plots import heatmap
    from sim2real.train import load_run

    _, args = config_lib.parse_args(argv)
    known = {"run", "x", "y", "episodes", "out", "seed"}
    for k in args:
        if k not in known:
            raise config_lib.ConfigError(f"unknown argument '{k}'; arguments: {', '.join(sorted(known))}")
    if "run" not in args or "x" not in args:
        raise config_lib.ConfigError("evaluate needs run=RUN_DIR and x=name=low:high:count")
    cfg, env, algo, state = load_run(str(args["run"]))
    axes = dict([parse_axis(str(args["x"]))] + ([parse_axis(str(args["y"]))] if "y" in args else []))
    zs, names = grid(env, axes, base=algo.space.base if hasattr(algo, "space") else None)
    env.check_z(zs)
    n_ep = int(args.get("episodes", 4))
    key = jax.random.PRNGKey(int(args.get("seed", 123)))
    rets = []
    for s in range(cfg.num_seeds):
        params, stats = algo.policy(jax.tree_util.tree_map(lambda x: x[s], state))
        rets.append(np.asarray(episodes(env, algo.ppo, params, stats, zs, key, n_ep)["return"]).mean(1))
    ret = np.mean(rets, 0).reshape([len(v) for v in axes.values()])
    out = str(args.get("out", os.path.join(str(args["run"]), "eval")))
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "returns.csv"), "w") as f:
        f.write(",".join(names) + ",return\n")
        for z, r in zip(zs, np.ravel(ret)):
            f.write(",".join(f"{z[env.spec.index(n)]:.6g}" for n in names) + f",{r:.6g}\n")
    box = {n: (lo, hi) for n, lo, hi in zip(cfg.dr.params, cfg.dr.low, cfg.dr.high)}
    heatmap(axes, ret, os.path.join(out, "returns.png"), title=f"{cfg.name}: mean return", box=box)
    print(f"wrote {out}/returns.csv and returns.png; mean return {ret.mean():.1f}, "
          f"min {ret.min():.1f}, max {ret.max():.1f}")


if __name__ == "__main__":
    main_guard(main, sys.argv[1:])
