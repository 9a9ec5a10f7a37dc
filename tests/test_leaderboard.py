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


def test_toy_leaderboard_runs_every_method_through_the_driver(tmp_path):
    spec = importlib.util.spec_from_file_location("bench_dr_leaderboard", os.path.join(ROOT, "benchmarks", "dr_leaderboard.py"))
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    from sim2real.common.config import load

    args = load(mod.Settings, ["methods=fixed,udr_context", "seeds=2", "scale=0.002", f"out={tmp_path}",
                               f"work={tmp_path / 'runs'}"])
    res = mod.main(args)
    n = len(mod.grid_points(mod.TASKS["pendulum"])[1])
    assert set(res["results"]) == {"fixed", "udr_context"} and res["results"]["fixed"].shape == (2, n)
    summary = (tmp_path / "pendulum" / "summary.md").read_text()
    assert "| fixed |" in summary and "| udr_context |" in summary
    assert (tmp_path / "pendulum" / "leaderboard.png").exists()
