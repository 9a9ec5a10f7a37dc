"""Evaluate a run's policy over a grid of physics values and draw a return heat map.

    python scripts/evaluate.py run=runs/pendulum_udr x=mass:pole=0.3:2.0:9 y=gain:motor=1:3:9 episodes=4

``x`` (and optionally ``y``) are ``name=low:high:count`` or ``name=v1,v2,...``; other parameters
stay at the run's fixed values. Writes ``<run>/eval/returns.csv`` and ``returns.png`` (the
training DR box is outlined). All seeds of the run are evaluated and averaged. The latest
checkpoint is evaluated, or ``policy.msgpack`` where the folder has no ``checkpoints/``.

``adapt=true`` (ES-MAML runs) first adapts the policy to each grid cell with the run's
adaptation operator (its inner PPO updates on that cell's physics), then evaluates (few-shot
evaluation, seed 004 Fig. 1); the un-adapted returns go to ``returns_before.csv``.
``progress=false`` hides the progress bar.
"""
import os
import sys

from sim2real.cli import main_guard


def main(argv):
    import jax
    import jax.numpy as jnp
    import numpy as np

    from sim2real import config as config_lib
    from sim2real import output
    from sim2real.evaluate import episodes, grid, parse_axis
    from sim2real.plots import heatmap
    from sim2real.progress import Bar
    from sim2real.train import load_policy, load_run

    args = config_lib.script_args(argv, {"run": "", "x": "", "y": "", "episodes": 4, "out": "", "seed": 123,
                                         "adapt": False, "progress": True})
    if not args["run"] or not args["x"]:
        raise config_lib.ConfigError("evaluate needs run=RUN_DIR and x=name=low:high:count")
    run = args["run"]
    if not os.path.isdir(run) or not os.path.exists(os.path.join(run, "config.yaml")):
        raise FileNotFoundError(f"run={run}: not a run folder (no config.yaml)")
    n_ep, seed = args["episodes"], args["seed"]
    if n_ep < 1:
        raise config_lib.ConfigError(f"episodes={n_ep!r}: must be a positive integer")
    axes = dict([parse_axis(args["x"])] + ([parse_axis(args["y"])] if args["y"] else []))
    out = args["out"] or os.path.join(run, "eval")
    output.check(out, "evaluation", inputs=[os.path.join(run, "config.yaml")], overwrite=True)
    if os.path.isdir(os.path.join(run, "checkpoints")):
        cfg, env, algo, state = load_run(run)
        all_params, all_stats = algo.policy(state)           # leading seed axis
    else:  # a run folder copied without its checkpoints: the exported policies
        cfg, env, algo, all_params, all_stats = load_policy(run)
    for n in axes:
        env.spec.index(n)  # an unknown name lists the known ones
    zs, names = grid(env, axes, base=algo.space.base if hasattr(algo, "space") else None)
    env.check_z(zs)
    adapt = args["adapt"]
    if adapt and not hasattr(algo, "adapt"):
        raise config_lib.ConfigError(f"adapt=true needs an algorithm with an adaptation operator "
                                     f"(es_maml); run '{args['run']}' trained algo '{cfg.algo}'")
    key = jax.random.PRNGKey(seed)
    shape = [len(v) for v in axes.values()]

    def cell_adapted(params, stats, z, k):
        # the same U as in meta-training, then the deterministic test episodes
        p2, s2, _ = algo.adapt(params, stats, z, jax.random.fold_in(k, 1))
        return episodes(env, algo.ppo, p2, s2, z[None], k, n_ep)["return"].mean()

    adapted = jax.jit(jax.vmap(cell_adapted, in_axes=(None, None, 0, None)))
    rets, before = [], []
    label = f"{len(zs)} physics x {n_ep} episodes" + (", adapted first" if adapt else "")
    with Bar(args["progress"], cfg.num_seeds * (1 + adapt), label) as bar:
        for s in range(cfg.num_seeds):
            params, stats = jax.tree_util.tree_map(lambda x: x[s], (all_params, all_stats))
            before.append(np.asarray(episodes(env, algo.ppo, params, stats, zs, key, n_ep)["return"]).mean(1))
            bar.step(text=f"seed {s}: evaluated")
            if adapt:
                rets.append(np.asarray(adapted(params, stats, jnp.asarray(zs), key)))
                bar.step(text=f"seed {s}: adapted and evaluated")
    ret = np.mean(rets if adapt else before, 0).reshape(shape)

    def write(path, values):
        with open(path, "w") as f:
            f.write(",".join(names) + ",return\n")
            for z, r in zip(zs, np.ravel(values)):
                f.write(",".join(f"{z[env.spec.index(n)]:.6g}" for n in names) + f",{r:.6g}\n")

    # written aside and moved into place when complete; only an evaluation folder is replaced
    with output.staged(out, "evaluation", inputs=[os.path.join(run, "config.yaml")], overwrite=True) as tmp:
        write(os.path.join(tmp, "returns.csv"), ret)
        if adapt:
            write(os.path.join(tmp, "returns_before.csv"), np.mean(before, 0))
        box = {n: (lo, hi) for n, lo, hi in zip(cfg.dr.params, cfg.dr.low, cfg.dr.high)}
        title = f"{cfg.name}: mean return" + (" after adaptation" if adapt else "")
        heatmap(axes, ret, os.path.join(tmp, "returns.png"), title=title, box=box)
    print(f"wrote {out}/returns.csv and returns.png; mean return {ret.mean():.1f}, "
          f"min {ret.min():.1f}, max {ret.max():.1f}"
          + (f" (before adaptation {np.mean(before):.1f})" if adapt else ""))


if __name__ == "__main__":
    main_guard(main, sys.argv[1:])
