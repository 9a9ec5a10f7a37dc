"""``make(name, **overrides)``: the one way to build an env by name."""
from __future__ import annotations

import importlib

from sim2real.envs.base import Env
from sim2real.physics.params import UnknownNameError, unknown_name_message

# name -> "module:Class" (imported lazily so a bad env never breaks the others)
ENVS = {
    "pendulum": "sim2real.envs.pendulum:Pendulum",
    "pendulum_balance": "sim2real.envs.pendulum:PendulumBalance",
    "cartpole": "sim2real.envs.cartpole:Cartpole",
    "cartpole_balance": "sim2real.envs.cartpole:CartpoleBalance",
    "hopper": "sim2real.envs.hopper:Hopper",
    "halfcheetah": "sim2real.envs.halfcheetah:HalfCheetah",
    "prismatic": "sim2real.envs.prismatic:PrismaticDrive",
    "arm2": "sim2real.envs.arm2:Arm2",
}


def env_class(name: str) -> type[Env]:
    if name not in ENVS:
        raise UnknownNameError(unknown_name_message("env", name, sorted(ENVS)))
    module, cls = ENVS[name].split(":")
    return getattr(importlib.import_module(module), cls)


def make(name: str, **overrides) -> Env:
    """Build env ``name``; ``overrides`` are :class:`~sim2real.envs.base.EnvConfig` fields."""
    return env_class(name)(**overrides)


def names() -> list[str]:
    return sorted(ENVS)
