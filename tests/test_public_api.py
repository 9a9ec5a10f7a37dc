"""The public fronts: curated exports that resolve, and ``import sim2real`` with no side effects."""
import importlib
import subprocess
import sys

import pytest

PACKAGES = ["sim2real", "sim2real.sysid", "sim2real.physics", "sim2real.algos", "sim2real.rl", "sim2real.training",
            "sim2real.tools", "sim2real.common", "sim2real.interop", "sim2real.commands"]


@pytest.mark.parametrize("package", PACKAGES)
def test_every_export_resolves(package):
    mod = importlib.import_module(package)
    assert mod.__all__
    for name in mod.__all__:
        assert getattr(mod, name) is not None, f"{package}.{name}"
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        getattr(mod, "nope")


def test_import_is_cheap_and_silent():
    code = (f"import sys, {', '.join(PACKAGES)}\n"
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
    from sim2real.common import config as config_lib
    from sim2real.algos import registry
    from sim2real.envs import make
    from sim2real.training.driver import TrainConfig

    registry.register("not_a_loop", lambda env, cfg: object())
    try:
        with pytest.raises(TypeError, match="not an OuterLoop"):
            registry.build("not_a_loop", make("pendulum"), config_lib.from_dict(TrainConfig, {}))
    finally:
        registry.BUILDERS.pop("not_a_loop")


# Each subpackage imports only from the layers below it (and itself): the driver above the
# algorithms, the algorithms above the PPO and the diagnosis, those above the envs.
LAYERS = {"common": 0, "physics": 0, "dists": 0, "envs": 1, "rl": 2, "sysid": 2, "algos": 3, "interop": 4,
          "training": 4, "tools": 5, "commands": 6}


def _sim2real_imports(path):
    import ast

    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("sim2real"):
            if node.module == "sim2real":
                yield from (f"sim2real.{a.name}" for a in node.names)
            else:
                yield node.module
        elif isinstance(node, ast.Import):
            yield from (a.name for a in node.names if a.name.startswith("sim2real"))


def test_subpackages_import_only_the_layers_below_them():
    import pathlib

    root = pathlib.Path(importlib.import_module("sim2real").__file__).parent
    found = {p.name for p in root.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert found == set(LAYERS), "a new subpackage needs its layer here"
    assert not [p.name for p in root.glob("*.py") if not p.name.startswith("_")], "loose top-level modules"
    for pkg, layer in LAYERS.items():
        for path in (root / pkg).rglob("*.py"):
            for mod in _sim2real_imports(path):
                target = mod.split(".")[1]
                if target.startswith("_") or target == pkg:
                    continue
                assert LAYERS[target] < layer, f"{path.relative_to(root)} imports {mod} (layer {target})"
