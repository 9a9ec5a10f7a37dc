"""Config files and key=value overrides, including the errors users see."""
import importlib.util
import os
import sys

import pytest

from sim2real.common import config as config_lib
from sim2real.common.config import ConfigError
from sim2real.training.driver import TrainConfig


def test_yaml_and_overrides(tmp_path):
    p = tmp_path / "c.yaml"
    p.write_text("env: hopper\nppo:\n  lr: 0.001\n  net: {hidden: [32, 32]}\n")
    cfg = config_lib.load(TrainConfig, [f"config={p}", "ppo.lr=3e-4", "ppo.net.use_context=true",
                                        "dr.params=[friction]", "dr.low=[0.5]", "dr.high=[1.5]", "num_seeds=3"])
    assert cfg.env == "hopper" and cfg.ppo.lr == 3e-4 and cfg.ppo.net.hidden == (32, 32)
    assert cfg.ppo.net.use_context is True and cfg.dr.params == ("friction",) and cfg.num_seeds == 3


def test_unknown_key_suggests_nearest():
    with pytest.raises(ConfigError) as e:
        config_lib.load(TrainConfig, ["ppo.learning_rate=1e-3"])
    assert "ppo.learning_rate" in str(e.value) and "ppo.lr" in str(e.value)
    with pytest.raises(ConfigError, match="total_steps"):
        config_lib.load(TrainConfig, ["total_step=10"])


def test_type_errors_name_the_key():
    with pytest.raises(ConfigError, match="ppo.num_envs"):
        config_lib.load(TrainConfig, ["ppo.num_envs=many"])
    with pytest.raises(ConfigError, match="resume"):
        config_lib.load(TrainConfig, ["resume=maybe"])
    with pytest.raises(ConfigError, match="not of the form"):
        config_lib.load(TrainConfig, ["ppo.lr"])


def test_missing_or_bad_file(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        config_lib.load(TrainConfig, [f"config={tmp_path / 'nope.yaml'}"])
    bad = tmp_path / "bad.yaml"
    bad.write_text("env: [unclosed\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        config_lib.load(TrainConfig, [f"config={bad}"])


def test_roundtrip(tmp_path):
    cfg = config_lib.load(TrainConfig, ["ppo.net.kind=lstm", "dr.fixed={gravity: 9.0}"])
    config_lib.save(cfg, tmp_path / "c.yaml")
    assert config_lib.load(TrainConfig, [f"config={tmp_path / 'c.yaml'}"]) == cfg


def test_every_bundled_training_config_builds_its_algorithm():
    """configs/*.yaml (SimOpt's too: one driver): keys valid, env and algorithm built (ES-MAML without
    its warm start, which points at a run the user trains first)."""
    import glob

    from sim2real.envs import make
    from sim2real.training.driver import TrainConfig, build_algo

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    paths = sorted(glob.glob(os.path.join(root, "configs", "*.yaml")))
    assert len(paths) >= 8 and sum("simopt" in os.path.basename(p) for p in paths) >= 2
    for p in paths:
        cfg = config_lib.load(TrainConfig, [f"config={p}"])
        if cfg.algo == "es_maml":
            cfg = config_lib.load(TrainConfig, [f"config={p}", "algo_options.warm_start=''"])
        algo = build_algo(cfg, make(cfg.env, **cfg.env_options))
        assert algo is not None, p


def test_progress_bar_closes_and_can_be_disabled():
    from sim2real.common.progress import Bar

    with Bar(True, 2, "work") as bar:
        bar.step()
        bar.step(text="done")
        assert bar.p.tasks[0].completed == 2
    assert not bar.enabled          # closed on exit
    off = Bar(False, 3, "quiet")
    off.step(2, "nothing drawn")
    off.close()
    assert not hasattr(off, "p")


def test_progress_bar_prints_stage_lines_where_output_is_not_a_terminal(capsys):
    """In a log file rich draws nothing until the bar stops; each stage then prints a line."""
    from sim2real.common.progress import Bar

    with Bar(True, 2, "diagnosis") as bar:
        assert bar.plain                 # pytest's captured stdout is not a terminal
        bar.step(text="fitting")
        bar.step(0, "candidate 1 of 9")  # a relabel inside quiet_s: no line
        bar.step(text="done")
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("[")]
    assert [ln.split("] ", 1)[1] for ln in lines] == ["diagnosis 1/2: fitting", "diagnosis 2/2: done"]


def test_settings_dataclasses_read_text_as_written_choices_and_required_keys():
    import dataclasses
    from typing import Any, Literal

    from sim2real.common.config import ConfigError, load, split

    @dataclasses.dataclass
    class S:
        part: Literal["a", "b"]
        steps: int = 100
        rate: float = 0.5
        tag: str = ""
        cases: tuple[str, ...] = ()
        plot: bool = False
        extra: dict[str, Any] = dataclasses.field(default_factory=dict)

    got = load(S, ["part=b", "steps=2e3", "rate=1", "tag=0.10", "cases=[x,y@z]", "plot=true", "extra.min_t=1.0"])
    assert got == S("b", 2000, 1.0, "0.10", ("x", "y@z"), True, {"min_t": 1.0})  # tag kept as written
    assert load(S, ["part=a", "cases=one"]).cases == ("one",)
    for bad, match in ((["part=c"], "part: 'c' is not one of a, b"),
                       ([], "missing required key part"),
                       (["part=a", "stepz=3"], "unknown config key 'stepz'. Did you mean: steps"),
                       (["part=a", "steps=2.5"], "steps: expected an integer"),
                       (["part=a", "rate=fast"], "rate: expected a number"),
                       (["part=a", "plot=maybe"], "plot: expected true/false"),
                       (["steps"], "not of the form key=value")):
        with pytest.raises(ConfigError, match=match):
            load(S, bad)
    mine, rest = split(["part=a", "ppo.lr=1e-3", "config=c.yaml", "extra.k=1"], S)
    assert mine == ["part=a", "extra.k=1"] and rest == ["ppo.lr=1e-3", "config=c.yaml"]


def test_every_benchmark_reads_its_settings_through_config_load():
    """Each benchmark script declares a ``Settings`` dataclass (no argparse, no ``sys.path`` edits)."""
    import pathlib

    from sim2real.common.config import ConfigError, load

    root = pathlib.Path(__file__).resolve().parents[1] / "benchmarks"
    for path in sorted(root.glob("*.py")):
        text = path.read_text()
        assert "argparse" not in text and "sys.path.insert" not in text, path.name
        if "def main(" not in text:
            continue  # a module of helpers (sysid_cases, plot_*)
        assert "class Settings" in text, path.name
    spec = importlib.util.spec_from_file_location("bench_reps_update", root / "reps_update.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    assert load(mod.Settings, ["real=[1,3,5]", "tag=h100"]).real == (1, 3, 5)
    with pytest.raises(ConfigError, match="Did you mean: samples"):
        load(mod.Settings, ["sample=5"])


def test_xla_cpu_flag_is_set_only_where_safe(monkeypatch):
    """sim2real turns XLA's CPU fusion emitters off on jaxlib 0.9 (a 7-link chain stepped 400x
    slower with them) -- never over a user's own setting, never once JAX has started."""
    import subprocess
    import sys
    from importlib.metadata import version

    import jax

    from sim2real import _xla_cpu

    jax.numpy.zeros(1).block_until_ready()  # backends up (with this process's real flags)
    monkeypatch.setenv("XLA_FLAGS", f"{_xla_cpu.FLAG}=true")
    assert not _xla_cpu.configure()
    assert os.environ["XLA_FLAGS"] == f"{_xla_cpu.FLAG}=true"   # the user's word stands
    monkeypatch.setenv("XLA_FLAGS", "")
    assert not _xla_cpu.configure()          # XLA has read its flags already: too late to matter
    assert os.environ["XLA_FLAGS"] == ""
    code = "import os, sim2real; print(os.environ['XLA_FLAGS'])"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env={**os.environ, "XLA_FLAGS": ""})
    want = f"{_xla_cpu.FLAG}=false" if version("jaxlib").startswith("0.9.") else ""
    assert r.stdout.strip() == want, r.stderr
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env={**os.environ, "XLA_FLAGS": f"{_xla_cpu.FLAG}=true"})
    assert r.stdout.strip() == f"{_xla_cpu.FLAG}=true", r.stderr

