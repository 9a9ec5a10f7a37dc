"""LSDR on hopper (seed 000), scaled to the device budget: learned ranges, evolution heat maps,
the Gaussian run, learned vs fixed DR at test time, EPOpt with learned vs uniform DR.

    python benchmarks/lsdr_hopper.py part=ranges     # Table I + Fig. 4: one run per parameter
    python benchmarks/lsdr_hopper.py part=gaussian   # Fig. 1d / 6: 4-D full-covariance Gaussian
    python benchmarks/lsdr_hopper.py part=transfer   # Fig. 8: LSDR vs fixed DR, fine-tuned on the test range
    python benchmarks/lsdr_hopper.py part=epopt      # Fig. 9: EPOpt-PPO with learned vs uniform DR
    python benchmarks/lsdr_hopper.py part=plots      # figures from the saved results (CPU)
    python benchmarks/lsdr_hopper.py part=table      # learned-range table from the saved results (CPU)
    ... scale=0.02                                   # tiny budgets, to check the script on CPU

Each part writes ``benchmarks/results/lsdr_hopper/<part>.npz`` / ``.csv`` (and ``part=plots``
the PNGs). Every run trains ``seeds`` seeds in one ``jit(vmap(scan))`` through the training
driver of ``scripts/train.py`` (run folders in ``work``; its ``test`` section evaluates the test
grid between chunks; fine-tuning starts from the trained run with ``algo_options.warm_start``). Priors are the paper's Table I boxes; values below a
parameter's physical lower bound (negative sizes, friction, damping) are clipped to it in the
simulator (README, bounds rule); with ``out_of_bounds=terminate`` such a context is a robot that
cannot exist instead: its episodes end at the first step with reward 0.
"""
from __future__ import annotations

import csv
import dataclasses
import json
import os
import sys
import time
from typing import Literal

import numpy as np

from sim2real.common.cli import settings

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "lsdr_hopper")
# Table I (hopper): initial train/test box and the paper's converged range
TABLE_I = {
    "torso_size": ((-0.1, 0.2), (0.0015, 0.09)),
    "density": ((10.0, 5000.0), (400.0, 4000.0)),
    "friction": ((-3.0, 10.0), (-3.0, 3.0)),
    "joint_damping": ((-10.0, 30.0), (-1.0, 26.0)),
}
PPO_BATCH = 4096 * 16
BASE = [  # GPU scale: 4096 envs x 16 steps per PPO update
    "env=hopper", "ppo.num_envs=4096", "ppo.num_steps=16", "ppo.num_epochs=4", "ppo.num_minibatches=8",
    "ppo.gamma=0.99", "ppo.lr=3e-4", "ppo.reward_scale=0.1", "ppo.net.hidden=[128,128]", "ppo.net.activation=tanh",
    "ppo.net.use_context=true", "tensorboard=false", "progress=false",
]


def config(extra: list[str], steps: float, a):
    """The run's ``TrainConfig``: ``BASE`` + ``extra`` with ``scale``, ``seeds`` and ``out_of_bounds`` of ``a``."""
    from sim2real.common import config as config_lib
    from sim2real.training.driver import TrainConfig

    args = BASE + [f"env_options.out_of_bounds={a.out_of_bounds}", f"total_steps={int(steps * a.scale)}",
                   f"num_seeds={a.seeds}"] + extra
    if a.scale < 1:  # CPU check of the script
        args += ["ppo.num_envs=64", "ppo.num_steps=16", "algo_options.num_contexts=8", "algo_options.eval_horizon=50"]
    return config_lib.load(TrainConfig, args)


def run(cfg, a, test_every: int = 0, test: tuple = (), warm_start: str = "", log=print):
    """Train ``cfg`` through the driver (run folder ``a.work/<name>``, replaced), the policy tested on
    the physics ``test = (names, grid)`` before every ``test_every``-th chunk and after the last
    (``TestConfig``: the grid clipped into the bounds, one episode per context and seed);
    ``warm_start``: a finished run folder whose policy starts this one (fine-tuning).

    Returns ``(run folder, rows, probs [C, S, D, bins] or None, dists [(mean, cov) per chunk])``: a
    row per chunk (train return, distribution entropy and evaluation return) and per test.
    """
    from sim2real.training.driver import train
    from sim2real.training.runs import TestConfig

    K, batch = cfg.updates_per_chunk, cfg.ppo.batch_size
    tc = TestConfig(every=test_every, params=tuple(test[0]), points=tuple(tuple(float(v) for v in g) for g in test[1]),
                    episodes=1, seed=7, out_of_bounds="clip") if test_every else TestConfig()
    opts = dict(cfg.algo_options, warm_start=warm_start) if warm_start else cfg.algo_options
    cfg = dataclasses.replace(cfg, out_dir=a.work, overwrite=True, test=tc, algo_options=opts)
    chunks, probs, dists = [], [], []
    t0 = time.time()

    def on_chunk(c, m):
        row = {"chunk": c + 1, "env_steps": (c + 1) * K * batch, "wall_seconds": round(time.time() - t0, 2),
               "train_return": float(np.nanmean(np.where(m["episodes"] > 0, m["episode_return"], np.nan))),
               "dist_entropy": float(np.nanmean(m["dist_entropy"])) if "dist_entropy" in m else np.nan,
               "dist_eval_return": float(np.nanmean(m["dist_eval_return"])) if "dist_eval_return" in m else np.nan}
        if "dist_probs" in m:
            probs.append(m["dist_probs"][:, -1])  # [S, D, bins] at the chunk's end
        if "dist_mean" in m:
            dists.append((m["dist_mean"][:, -1], m["dist_cov"][:, -1]))
        chunks.append(row)
        log(f"  chunk {c + 1}: {row['env_steps']:,} steps, train return {row['train_return']:.0f}, "
            f"{row['wall_seconds']:.0f} s")

    out = train(cfg, on_chunk)
    tests = {}
    if test_every:
        with np.load(os.path.join(out["run_dir"], "test.npz")) as f:
            tests = {int(c): {"test_return": float(r.mean()), "test_grid": r.tolist()}
                     for c, r in zip(f["chunk"], f["returns"])}
    rows = []
    for row in chunks:  # a test before a chunk is its own row; the one after the last joins its row
        c = row["chunk"] - 1
        if c in tests:
            rows.append({"chunk": c, "env_steps": c * K * batch, **tests[c]})
        rows.append(dict(row, **tests.get(row["chunk"], {})) if row["chunk"] == len(chunks) else row)
    return out["run_dir"], rows, (np.stack(probs) if probs else None), dists


def uniform_fit(centers, p):
    """Moment-matched uniform range of a binned distribution: mean +- sqrt(3) std."""
    m = float((centers * p).sum())
    s = float(np.sqrt(((centers - m) ** 2 * p).sum()))
    return m - np.sqrt(3) * s, m + np.sqrt(3) * s


def quantile_range(centers, p, q=0.05):
    """Central ``1 - 2q`` probability range of a binned distribution (bin centres)."""
    cdf = np.cumsum(p)
    return float(centers[np.searchsorted(cdf, q)]), float(centers[min(np.searchsorted(cdf, 1 - q), len(centers) - 1)])


def part_table(a, log):
    """Per parameter, from the saved ``ranges_<name>.npz`` in ``out``: the moment-matched uniform,
    the central 90% range and the probability p_phi puts on values below the physical lower bound
    (robots that cannot exist), mean over seeds; written to ``ranges_table.csv``."""
    from sim2real.envs import make

    spec = make("hopper").spec
    rows = []
    for name, (prior, conv) in TABLE_I.items():
        path = os.path.join(a.out, f"ranges_{name}.npz")
        if not os.path.exists(path):
            continue
        d = np.load(path)
        p = d["probs"][-1][:, 0]  # [S, bins] at the end of training
        centers = (d["edges"][1:] + d["edges"][:-1]) / 2
        low = float(spec.low[spec.index(name)])
        mm = np.mean([uniform_fit(centers, q) for q in p], 0)
        qr = np.mean([quantile_range(centers, q) for q in p], 0)
        rows.append({"parameter": name, "prior_low": prior[0], "prior_high": prior[1],
                     "paper_low": conv[0], "paper_high": conv[1], "moment_low": mm[0], "moment_high": mm[1],
                     "q05": qr[0], "q95": qr[1], "physical_low": low,
                     "prior_mass_below_physical": float(np.mean(centers < low)),
                     "p_phi_mass_below_physical": float(np.mean([q[centers < low].sum() for q in p]))})
        r = rows[-1]
        log(f"{name}: moment-matched [{mm[0]:.4g}, {mm[1]:.4g}], 5-95% [{qr[0]:.4g}, {qr[1]:.4g}], "
            f"mass below {low:g}: {r['p_phi_mass_below_physical']:.3f} (prior {r['prior_mass_below_physical']:.2f}); "
            f"paper {conv}")
    write_csv(os.path.join(a.out, "ranges_table.csv"), rows)


def write_csv(path, rows):
    keys = list(dict.fromkeys(k for r in rows for k in r if k != "test_grid"))
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


def part_ranges(a, log):
    """One LSDR run per parameter, 100-bin distribution over the Table I box."""
    summary = {}
    for name, (prior, conv) in TABLE_I.items():
        if a.only and a.only != name:
            continue
        log(f"LSDR binned, {name} over {prior}")
        cfg = config([f"name=lsdr_{name}", "algo=lsdr", f"dr.params=[{name}]", f"dr.low=[{prior[0]}]",
                      f"dr.high=[{prior[1]}]", "algo_options.dist=binned", "algo_options.num_bins=100",
                      f"algo_options.num_contexts={a.contexts}", f"algo_options.dist_every={a.dist_every}",
                      f"algo_options.dist_start={a.dist_start}", f"updates_per_chunk={a.chunk}",
                      f"algo_options.alpha={a.alpha}"],
                     a.steps, a)
        _, rows, probs, _ = run(cfg, a, log=log)
        edges = np.linspace(prior[0], prior[1], probs.shape[-1] + 1)
        centers = (edges[1:] + edges[:-1]) / 2
        fits = [uniform_fit(centers, probs[-1, s, 0]) for s in range(probs.shape[1])]
        summary[name] = {"prior": prior, "paper_converged": conv, "learned_per_seed": fits,
                         "learned_mean": np.mean(fits, 0).tolist(), "learned_std": np.std(fits, 0).tolist(),
                         "out_of_bounds": a.out_of_bounds,
                         "final_train_return": rows[-1]["train_return"], "env_steps": rows[-1]["env_steps"],
                         "wall_seconds": rows[-1]["wall_seconds"]}
        np.savez(os.path.join(a.out, f"ranges_{name}.npz"), probs=probs, edges=edges,
                 env_steps=np.array([r["env_steps"] for r in rows]))
        write_csv(os.path.join(a.out, f"ranges_{name}.csv"), rows)
        log(f"  learned range {summary[name]['learned_mean']} (paper {conv})")
    path = os.path.join(a.out, "ranges_summary.json")
    old = json.load(open(path)) if os.path.exists(path) else {}
    old.update(summary)
    with open(path, "w") as f:
        json.dump(old, f, indent=2)


GRID_PAIR = ("torso_size", "friction")  # the 2-D test grid of the Gaussian part (Fig. 1b-d)


def part_gaussian(a, log):
    """4-D full-covariance Gaussian LSDR (Fig. 1c-d) and uniform DR over the same box (Fig. 1b).

    Both final policies are evaluated on a 10 x 10 grid over the prior box of ``GRID_PAIR`` (the
    other two parameters at the hopper's defaults). The paper samples the Gaussian's score term
    from p_phi ("for the experiments with multivariate Gaussian distributions changing the
    sampling distribution was not required"): ``sample_from=learned`` is this part's default.
    """
    names = list(TABLE_I)
    lo = [TABLE_I[n][0][0] for n in names]
    hi = [TABLE_I[n][0][1] for n in names]
    axes = [np.linspace(TABLE_I[n][0][0], TABLE_I[n][0][1], 10) for n in GRID_PAIR]
    grid = [[u, v] for u in axes[0] for v in axes[1]]
    path = os.path.join(a.out, f"gaussian{a.tag}_grid.json")
    result = json.load(open(path)) if os.path.exists(path) else {}
    for algo in a.algos.split(","):
        # fixed DR is the uniform prior itself (Fig. 1b): a binned distribution starts uniform
        dist = "gaussian" if algo == "lsdr" else "binned"
        log(f"{algo}: {dist} over the 4-D Table I box, score samples from {a.sample_from}")
        cfg = config([f"name=gauss_{algo}", f"algo={algo}", f"dr.params=[{','.join(names)}]", f"dr.low={lo}",
                      f"dr.high={hi}", f"algo_options.dist={dist}", f"algo_options.num_contexts={a.contexts}",
                      f"algo_options.alpha={a.alpha}", f"algo_options.sample_from={a.sample_from}",
                      f"algo_options.center={a.center}", f"algo_options.lr={a.dist_lr}",
                      f"algo_options.dist_every={a.dist_every}", f"algo_options.dist_start={a.dist_start}",
                      f"updates_per_chunk={a.chunk}"], a.steps, a)
        _, rows, _, dists = run(cfg, a, 10**9, (GRID_PAIR, grid), log=log)  # test first and last
        final = rows[-1]
        log(f"  grid return {final['test_return']:.0f} (mean over {len(grid)} contexts and {a.seeds} seeds)")
        result[algo] = {"test_grid": final["test_grid"], "test_return": final["test_return"],
                        "train_return": final["train_return"]}
        if algo == "lsdr":
            np.savez(os.path.join(a.out, f"gaussian{a.tag}.npz"), names=np.array(names), low=np.array(lo),
                     high=np.array(hi), mean=np.stack([d[0] for d in dists]), cov=np.stack([d[1] for d in dists]),
                     env_steps=np.array([r["env_steps"] for r in rows if "wall_seconds" in r]))
            write_csv(os.path.join(a.out, f"gaussian{a.tag}.csv"), rows)
        result["grid"] = {"names": list(GRID_PAIR), "axes": [x.tolist() for x in axes]}
        result.setdefault("settings", {})[algo] = {"steps": a.steps, "seeds": a.seeds, "alpha": a.alpha,
                                                   "sample_from": a.sample_from, "dist": dist,
                                                   "center": a.center, "dist_lr": a.dist_lr}
        with open(path, "w") as f:
            json.dump(result, f)


def part_transfer(a, log, optimizer="ppo"):
    """Learned vs fixed DR on torso size; then both fine-tuned on the full test range (Fig. 8)."""
    prior = TABLE_I["torso_size"][0]
    grid = [[g] for g in np.linspace(prior[0], prior[1], 16)]
    tag = "transfer" if optimizer == "ppo" else "epopt"
    path = os.path.join(a.out, f"{tag}.json")
    # one device call may run one algorithm (algos): merge into what earlier calls wrote
    result = json.load(open(path)) if os.path.exists(path) else {}
    extra_opt = [] if optimizer == "ppo" else ["algo_options.policy_optimizer=epopt",
                                               f"algo_options.epopt.num_contexts={a.epopt_contexts}"]
    for algo in a.algos.split(","):
        log(f"{algo} ({optimizer}) on torso size over {prior}")
        cfg = config([f"name={tag}_{algo}", f"algo={algo}", "dr.params=[torso_size]", f"dr.low=[{prior[0]}]",
                      f"dr.high=[{prior[1]}]", "algo_options.dist=binned", f"algo_options.num_contexts={a.contexts}",
                      f"algo_options.dist_every={a.dist_every}", f"algo_options.dist_start={a.dist_start}",
                      f"updates_per_chunk={a.chunk}"] + extra_opt, a.steps, a)
        trained, rows, probs, _ = run(cfg, a, a.eval_every, (["torso_size"], grid), log=log)
        result[algo] = {"train": rows}
        if optimizer == "ppo":
            log(f"  fine-tuning {algo} on the test range (fixed uniform DR over it)")
            ft = config([f"name={tag}_{algo}_ft", "algo=fixed_dr", "dr.params=[torso_size]", f"dr.low=[{prior[0]}]",
                         f"dr.high=[{prior[1]}]", f"updates_per_chunk={a.chunk}"], a.ft_steps, a)
            _, ft_rows, _, _ = run(ft, a, a.eval_every, (["torso_size"], grid), warm_start=trained, log=log)
            result[algo]["finetune"] = ft_rows
        if probs is not None:
            np.savez(os.path.join(a.out, f"{tag}_{algo}_probs.npz"), probs=probs)
        result["grid"] = grid
        result.setdefault("settings", {})[algo] = {"steps": a.steps, "seeds": a.seeds, "chunk": a.chunk,
                                                   "epopt_contexts": a.epopt_contexts if optimizer == "epopt" else None}
        with open(path, "w") as f:
            json.dump(result, f)


def ellipse(cov2, radius: float, n: int = 100):
    """``[2, n]`` offsets from the mean of the ``radius``-Mahalanobis contour of a 2-D covariance."""
    w, v = np.linalg.eigh(cov2)
    th = np.linspace(0, 2 * np.pi, n)
    return v @ (radius * np.sqrt(np.maximum(w, 0))[:, None] * np.stack([np.cos(th), np.sin(th)]))


def plot_gaussian_grid(res, gauss, path):
    """Heat maps of the final policies' return over ``GRID_PAIR`` (mean over seeds), uniform DR and
    LSDR, with the learned Gaussian's 68/95/99% confidence regions of that pair (seed 0)."""
    import matplotlib.pyplot as plt

    names, (u, v) = res["grid"]["names"], res["grid"]["axes"]
    algos = [k for k in ("fixed_dr", "lsdr") if k in res]
    fig, axes = plt.subplots(1, len(algos), figsize=(5.2 * len(algos), 4.2), squeeze=False)
    vmax = max(np.max(np.mean(res[k]["test_grid"], 0)) for k in algos)
    for ax, k in zip(axes[0], algos):
        g = np.mean(res[k]["test_grid"], 0).reshape(len(u), len(v))  # [torso, friction]
        du, dv = (u[1] - u[0]) / 2, (v[1] - v[0]) / 2
        im = ax.imshow(g.T, origin="lower", aspect="auto", cmap="viridis", vmin=0, vmax=vmax,
                       extent=[u[0] - du, u[-1] + du, v[0] - dv, v[-1] + dv])
        fig.colorbar(im, ax=ax, label="return")
        label = {"fixed_dr": "uniform DR", "lsdr": "learned Gaussian DR"}[k]
        ax.set_title(f"{label}: mean {np.mean(res[k]['test_grid']):.0f}")
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1])
        if k == "lsdr" and gauss is not None:
            order = list(gauss["names"])
            i, j = order.index(names[0]), order.index(names[1])
            m, c = gauss["mean"][-1, 0][[i, j]], gauss["cov"][-1, 0][np.ix_([i, j], [i, j])]
            for conf, chi2 in ((68, 2.279), (95, 5.991), (99, 9.210)):  # chi-square(2) quantiles
                e = ellipse(c, np.sqrt(chi2))
                ax.plot(m[0] + e[0], m[1] + e[1], "w", lw=1)
                ax.annotate(f"{conf}%", (m[0] + e[0, 25], m[1] + e[1, 25]), color="w", fontsize=7)
            ax.set_xlim(u[0] - du, u[-1] + du)
            ax.set_ylim(v[0] - dv, v[-1] + dv)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def part_plots(a, log):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [n for n in TABLE_I if os.path.exists(os.path.join(a.out, f"ranges_{n}.npz"))]
    if names:  # Fig. 4: evolution of p_phi per parameter (seed 0)
        fig, axes = plt.subplots(1, len(names), figsize=(4 * len(names), 3.4), squeeze=False)
        for ax, n in zip(axes[0], names):
            d = np.load(os.path.join(a.out, f"ranges_{n}.npz"))
            p = d["probs"][:, 0, 0]  # [C, bins]
            ax.imshow(p.T, origin="lower", aspect="auto", cmap="magma",
                      extent=[0, d["env_steps"][-1] / 1e6, d["edges"][0], d["edges"][-1]])
            conv = TABLE_I[n][1]
            for v in conv:
                ax.axhline(v, color="c", ls="--", lw=1)
            ax.set_title(f"{n} (dashed: paper's range)")
            ax.set_xlabel("env steps [M]")
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, "evolution.png"), dpi=110)
    gp = os.path.join(a.out, f"gaussian{a.tag}.npz")
    if os.path.exists(gp):  # Fig. 1d / 6: Gaussian marginals over time and final 2-sigma ellipses
        d = np.load(gp)
        names_g, mean, cov = list(d["names"]), d["mean"][:, 0], d["cov"][:, 0]
        fig, axes = plt.subplots(1, len(names_g) + 1, figsize=(4 * (len(names_g) + 1), 3.4))
        x = d["env_steps"] / 1e6
        for k, (ax, n) in enumerate(zip(axes, names_g)):
            sd = np.sqrt(cov[:, k, k])
            ax.plot(x, mean[:, k], "k")
            ax.fill_between(x, mean[:, k] - 2 * sd, mean[:, k] + 2 * sd, alpha=0.3)
            ax.axhspan(d["low"][k], d["high"][k], color="0.9", zorder=-1)
            ax.set_title(f"{n}: mean +- 2 sd")
            ax.set_xlabel("env steps [M]")
        ax = axes[-1]
        i, j = 0, 2  # torso size vs friction
        for t, col in ((0, "0.6"), (len(mean) - 1, "C3")):
            e = ellipse(cov[t][np.ix_([i, j], [i, j])], 2.0)
            ax.plot(mean[t, i] + e[0], mean[t, j] + e[1], color=col, label="start" if t == 0 else "end")
        ax.set_xlabel(names_g[i])
        ax.set_ylabel(names_g[j])
        ax.set_title("2-sd confidence region")
        ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, f"gaussian{a.tag}.png"), dpi=110)
    gg = os.path.join(a.out, f"gaussian{a.tag}_grid.json")
    if os.path.exists(gg):  # Fig. 1b-d: grid returns of uniform vs learned DR, learned confidence regions
        plot_gaussian_grid(json.load(open(gg)), np.load(gp) if os.path.exists(gp) else None,
                           os.path.join(a.out, f"gaussian{a.tag}_grid.png"))
    for tag, title in (("transfer", "torso size: test-range return (Fig. 8)"), ("epopt", "EPOpt, torso size (Fig. 9)")):
        p = os.path.join(a.out, f"{tag}.json")
        if not os.path.exists(p):
            continue
        d = json.load(open(p))
        fig, ax = plt.subplots(figsize=(6, 3.6))
        for algo, col in (("lsdr", "C3"), ("fixed_dr", "C0")):
            if algo not in d:
                continue
            rows = [r for r in d[algo]["train"] if "test_grid" in r]
            # EPOpt's updates run num_contexts whole episodes each, not the PPO batch the
            # env_steps column counts: its axis is PPO updates
            x = np.array([r["env_steps"] for r in rows]) / (PPO_BATCH if tag == "epopt" else 1e6)
            g = np.array([np.mean(r["test_grid"], 1) for r in rows])  # [E, S] mean over the grid
            ax.plot(x, g.mean(1), color=col, label=f"{algo} (training)")
            ax.fill_between(x, g.min(1), g.max(1), color=col, alpha=0.2)
            if "finetune" in d[algo]:
                f_rows = [r for r in d[algo]["finetune"] if "test_grid" in r]
                xf = x[-1] + np.array([r["env_steps"] for r in f_rows]) / 1e6
                gf = np.array([np.mean(r["test_grid"], 1) for r in f_rows])
                ax.plot(xf, gf.mean(1), color=col, ls="--", label=f"{algo} (fine-tuned on test range)")
                ax.fill_between(xf, gf.min(1), gf.max(1), color=col, alpha=0.1)
        ax.set_xlabel("PPO updates (worst 10% of 1000 episodes each)" if tag == "epopt" else "env steps [M]")
        ax.set_ylabel("mean return over the test range")
        ax.set_title(title)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, f"{tag}.png"), dpi=110)


@dataclasses.dataclass
class Settings:
    """part (required): what to run. only: (ranges) one parameter; steps: env steps per seed per run;
    ft_steps: fine-tuning steps; seeds; contexts: K, episodes per distribution update;
    epopt_contexts; dist_every, dist_start: distribution updates every/after so many PPO updates;
    chunk: PPO updates per jitted chunk; eval_every: chunks between test evaluations (the driver's ``test``); scale:
    multiplies every budget; alpha: (ranges/gaussian) LSDR's KL(p || p_phi) weight; algos:
    (gaussian/transfer/epopt) which runs, comma-separated; sample_from: (gaussian) where the score
    term's contexts come from (the paper: learned p_phi); center: (gaussian) centre the returns by
    their running mean (ema, the paper) or the batch mean; dist_lr: (gaussian) Adam step on phi;
    out: results folder; work: the runs' folders (replaced); tag: (gaussian) suffix of the result files; out_of_bounds: physics outside
    the parameters' bounds: simulate the bound (clip), or end the episode at once with reward 0
    (terminate; the paper's simulator: negative sizes/masses fail)."""
    part: Literal["ranges", "gaussian", "transfer", "epopt", "plots", "table"]
    only: str = ""
    steps: float = 30e6
    ft_steps: float = 10e6
    seeds: int = 2
    contexts: int = 64
    epopt_contexts: int = 1000
    dist_every: int = 4
    dist_start: int = 40
    chunk: int = 25
    eval_every: int = 2
    scale: float = 1.0
    alpha: float = 1.0
    algos: str = "lsdr,fixed_dr"
    sample_from: Literal["learned", "prior"] = "learned"
    center: Literal["ema", "batch"] = "ema"
    dist_lr: float = 0.05
    out: str = OUT
    work: str = "/tmp/lsdr_hopper_runs"
    tag: str = ""
    out_of_bounds: Literal["clip", "terminate"] = "clip"


def main(a: Settings):
    os.makedirs(a.out, exist_ok=True)
    import jax

    t0 = time.time()
    log = lambda s: print(f"[{time.time() - t0:6.0f}s] {s}", flush=True)  # noqa: E731
    log(f"device: {jax.devices()[0].device_kind}; part {a.part}; out_of_bounds={a.out_of_bounds}; "
        f"args {vars(a)}")
    {"ranges": part_ranges, "gaussian": part_gaussian, "transfer": part_transfer,
     "epopt": lambda a, log: part_transfer(a, log, "epopt"), "plots": part_plots, "table": part_table}[a.part](a, log)
    log("done")


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
