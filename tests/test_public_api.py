"""The public fronts: curated exports that resolve, and ``import sim2real`` with no side effects."""
import importlib
import subprocess
import sys

import pytest

PACKAGES = ["sim2real", "sim2real.sysid", "sim2real.physics", "sim2real.algos", "sim2real.rl"]


@pytest.mark.parametrize("package", PACKAGES)
def test_every_export_resolves(package):
    mod = importlib.import_module(package)
    assert mod.__all__
    for name in mod.__all__:
        assert getattr(mod, name) is not None, f"{package}.{name}"
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        getattr(mod, "nope")


def test_import_is_cheap_and_silent():
    code = ("import sys, sim2real, sim2real.sysid, sim2real.physics, sim2real.algos, sim2real.rl\n"
            "heavy = [m for m in ('jax', 'mujoco', 'mujoco.mjx', 'flax') if m in sys.modules]\n"
            "assert not heavy, heavy\n"
            "print(sim2real.__version__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == importlib.import_module("sim2real").__version__  # nothing else printed


def test_mjx_import_drops_only_the_missing_warp_lines():
    code = "from sim2real._mjx import mjx; print('ok', mjx.__name__)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok mujoco.mjx"


def test_an_algorithm_must_meet_the_outer_loop_contract():
    from sim2real import config as config_lib
    from sim2real.algos import registry
    from sim2real.envs import make
    from sim2real.train import TrainConfig

    registry.register("not_a_loop", lambda env, cfg: object())
    try:
        with pytest.raises(TypeError, match="not an OuterLoop"):
            registry.build("not_a_loop", make("pendulum"), config_lib.from_dict(TrainConfig, {}))
    finally:
        registry.BUILDERS.pop("not_a_loop")


def test_no_algorithm_imports_the_driver():
    """The driver sits above the algorithms: none of them imports ``sim2real.train``."""
    import pathlib

    root = pathlib.Path(importlib.import_module("sim2real.algos").__file__).parent
    for path in root.glob("*.py"):
        text = path.read_text()
        assert "sim2real.train" not in text and "from sim2real import train" not in text, path.name
