"""The out-of-distribution leaderboard: its statistics on known arrays, and the toy CPU run."""
import importlib.util
import os
import sys

import numpy as np
import pytest

from sim2real.tools import leaderboard

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_intervals_cover_the_mean_and_differences_are_called_significant_only_when_they_are():
    rng = np.random.default_rng(1)
    in_box = np.array([True, True, False, False, False])
    a = rng.normal(100.0, 5.0, (5, 5))
    s = leaderboard.grid_stats(a, in_box, threshold=100.0)
    for region in leaderboard.REGIONS:
        assert s[region]["low"] <= s[region]["mean"] <= s[region]["high"]
    assert s["in_box"]["mean"] == pytest.approx(a[:, :2].mean())
    assert s["above_threshold"] == pytest.approx((a >= 100).mean())
    assert leaderboard.difference(a + 50.0, a, in_box)["significant"]
    same = leaderboard.difference(a, rng.normal(100.0, 5.0, (5, 5)), in_box)
    assert not same["significant"] and same["low"] < 0 < same["high"]
    text = leaderboard.table({"worse": a, "better": a + 50.0}, in_box, 100.0)
    rows = text.strip().splitlines()
    assert rows[2].startswith("| better |") and rows[3].startswith("| worse |") and "significant" in rows[3]
    with pytest.raises(ValueError, match="NaN"):
        leaderboard.grid_stats(np.full((2, 5), np.nan), in_box, 0.0)


def _load(name):
    spec = importlib.util.spec_from_file_location(f"bench_{name}", os.path.join(ROOT, "benchmarks", f"{name}.py"))
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.slow  # ~100 s: the benchmark script end to end; every method's settings are built in the fast set
def test_toy_leaderboard_runs_every_method_through_the_driver(tmp_path):
    mod = _load("dr_leaderboard")
    from sim2real.common.config import load

    args = load(mod.Settings, ["methods=fixed,adr", "seeds=2", "scale=0.002", f"out={tmp_path}",
                               f"work={tmp_path / 'runs'}"])
    res = mod.main(args)
    n = len(mod.grid_points(mod.TASKS["pendulum"])[1])
    assert set(res["results"]) == {"fixed", "adr"} and res["results"]["fixed"].shape == (2, n)
    summary = (tmp_path / "pendulum" / "summary.md").read_text()
    assert "| fixed |" in summary and "| adr |" in summary
    assert (tmp_path / "pendulum" / "leaderboard.png").exists()
    # the learned box's evolution, from the ADR run folder
    plot = _load("dr_learned_plot")
    png = plot.main(plot.Settings(adr=str(tmp_path / "runs" / "adr"), out=str(tmp_path / "learned.png")))
    assert os.path.getsize(png) > 0


def test_every_leaderboard_method_builds_on_both_tasks():
    """The placeholders of METHODS (boxes, limit boxes, thresholds) give settings every algorithm
    accepts, on the pendulum and on hopper (nothing is trained)."""
    from sim2real.common.config import load
    from sim2real.envs import make
    from sim2real.training.driver import TrainConfig, build_algo

    mod = _load("dr_leaderboard")
    for task_name, task in mod.TASKS.items():
        env = make(task_name)
        for method in mod.METHODS:
            cfg = load(TrainConfig, [f"config={os.path.join(ROOT, task['config'])}", "ppo.num_envs=8",
                                     "ppo.num_steps=8", "ppo.num_minibatches=2"]
                       + mod.method_args(method, task, task["threshold"]))
            assert build_algo(cfg, env).space.names == tuple(task["box"]) or method == "fixed"
