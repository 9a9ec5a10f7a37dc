"""``make(name, **overrides)``: the one way to build an env by name.

An env is found by its ``name``: every module of ``sim2real.envs`` is imported on the first lookup
and each ``Env`` subclass that sets its own ``name`` is registered, so adding an env is its
module (plus its test), not a line here. ``playground:<Task>`` names a MuJoCo Playground task
(``sim2real/envs/playground.py``).
"""
from __future__ import annotations

import importlib
import pkgutil

from sim2real.envs.base import Env
from sim2real.physics.params import UnknownNameError, unknown_name_message

_ENVS: dict[str, type[Env]] = {}


def _load_all() -> dict[str, type[Env]]:
    if not _ENVS:
        import sim2real.envs as pkg

        for m in pkgutil.iter_modules(pkg.__path__):
            mod = importlib.import_module(f"{pkg.__name__}.{m.name}")
            for obj in vars(mod).values():
                if (isinstance(obj, type) and issubclass(obj, Env) and obj is not Env and obj.__module__ == mod.__name__
                        and "name" in vars(obj)):
                    if obj.name in _ENVS:
                        raise RuntimeError(f"env name '{obj.name}' is taken by both {_ENVS[obj.name].__qualname__} "
                                           f"and {obj.__qualname__}")
                    _ENVS[obj.name] = obj
    return _ENVS


def env_class(name: str) -> type[Env]:
    from sim2real.envs import playground

    if playground.is_playground(name):  # a MuJoCo Playground task, read into a ParamSpec
        return playground.env_class(name)
    envs = _load_all()
    if name not in envs:
        raise UnknownNameError(unknown_name_message("env", name, sorted(envs)))
    return envs[name]


def make(name: str, **overrides) -> Env:
    """Build env ``name``; ``overrides`` are :class:`~sim2real.envs.base.EnvConfig` fields."""
    return env_class(name)(**overrides)


def names() -> list[str]:
    return sorted(_load_all())
