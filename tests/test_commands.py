"""The command line: ``-h`` lists every key with its type, default and doc; console entry points
and ``python -m sim2real``; bundled configs by name."""
import importlib
import os
import tomllib

import pytest

from sim2real.common import config as config_lib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_help_lists_every_key_with_type_default_and_doc(capsys):
    from sim2real.commands import train
    from sim2real.training.runs import TrainConfig

    train.run(["-h"])
    out = capsys.readouterr().out
    assert out.startswith("Train a policy")
    lines = {line.split()[0]: line for line in out.splitlines() if line.startswith("  ")}
    for key in config_lib.all_keys(TrainConfig):
        if key not in ("ppo", "ppo.net", "dr", "test"):  # sections: their keys are listed
            assert key in lines, key
    assert lines["ppo.lr"].split()[1:4] == ["float", "0.0003", "Adam"]
    assert "Literal['refuse', 'clip']" in lines["test.out_of_bounds"]


def test_every_console_entry_point_and_python_m(capsys):
    from sim2real.__main__ import main
    from sim2real.commands import COMMANDS

    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as f:
        scripts = tomllib.load(f)["project"]["scripts"]
    assert sorted(scripts) == sorted(f"sim2real-{c}" for c in COMMANDS)
    for name, target in scripts.items():
        module, fn = target.split(":")
        assert callable(getattr(importlib.import_module(module), fn)), name
    assert main([]) == 0 and "python -m sim2real {train," in capsys.readouterr().out
    assert main(["nope"]) == 2
    main(["evaluate", "-h"])
    assert "keys of EvaluateConfig" in capsys.readouterr().out


def test_bundled_configs_by_name(tmp_path, monkeypatch):
    from sim2real.training.runs import TrainConfig

    monkeypatch.chdir(tmp_path)  # away from the repository's configs/
    cfg = config_lib.load(TrainConfig, ["config=pendulum"])
    assert cfg.env == "pendulum" and cfg.total_steps == 1_500_000
    with pytest.raises(config_lib.ConfigError, match="bundled: .*cartpole.*pendulum"):
        config_lib.load(TrainConfig, ["config=nope"])
    with pytest.raises(config_lib.ConfigError, match="'nope.yaml' not found"):
        config_lib.load(TrainConfig, ["config=nope.yaml"])


def test_the_commands_keep_compiled_programs_where_the_environment_says():
    """``common/compile_cache``: the folder from ``SIM2REAL_COMPILE_CACHE`` (``off``: none), else
    under ``XDG_CACHE_HOME`` or ``~/.cache``; a cache folder already set (the user's, or this test
    session's own from conftest) is left as it is."""
    import jax

    from sim2real.common import compile_cache as cc

    assert cc.cache_dir({"SIM2REAL_COMPILE_CACHE": "/data/xla"}) == "/data/xla"
    assert cc.cache_dir({"SIM2REAL_COMPILE_CACHE": "off", "XDG_CACHE_HOME": "/c"}) is None
    assert cc.cache_dir({"XDG_CACHE_HOME": "/c"}) == os.path.join("/c", "sim2real", "xla")
    assert cc.cache_dir({}) == os.path.join(os.path.expanduser("~"), ".cache", "sim2real", "xla")
    before = jax.config.jax_compilation_cache_dir
    assert before  # conftest's per-session folder
    assert cc.enable() == before and jax.config.jax_compilation_cache_dir == before
