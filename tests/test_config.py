"""Config files and key=value overrides, including the errors users see."""
import os

import pytest

from sim2real import config as config_lib
from sim2real.config import ConfigError
from sim2real.train import TrainConfig


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
    from sim2real.train import TrainConfig, build_algo

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
    from sim2real.progress import Bar

    with Bar(True, 2, "work") as bar:
        bar.step()
        bar.step(text="done")
        assert bar.p.tasks[0].completed == 2
    assert not bar.enabled          # closed on exit
    off = Bar(False, 3, "quiet")
    off.step(2, "nothing drawn")
    off.close()
    assert not hasattr(off, "p")


def test_script_args_convert_to_the_defaults_types_and_name_bad_keys():
    from sim2real.config import ConfigError, script_args, split_args

    d = {"steps": 100, "rate": 0.5, "out": "", "plot": False}
    got = script_args(["steps=2e3", "rate=1", "out=a=b", "plot=true"], d)
    assert got == {"steps": 2000, "rate": 1.0, "out": "a=b", "plot": True}
    assert d["steps"] == 100  # the defaults are not changed
    own, rest = split_args(["steps=5", "ppo.lr=1e-3"], d)
    assert own["steps"] == 5 and rest == ["ppo.lr=1e-3"]
    for bad, match in ((["stepz=3"], "unknown argument 'stepz'; arguments: out, plot, rate, steps"),
                       (["steps=2.5"], "steps='2.5': must be int"),
                       (["rate=fast"], "rate='fast': must be float"),
                       (["plot=maybe"], "plot='maybe': must be bool"),
                       (["steps"], "not of the form key=value")):
        with pytest.raises(ConfigError, match=match):
            script_args(bad, d)
