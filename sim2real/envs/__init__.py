"""MJX environments with per-environment physics (see base.py for the conventions)."""
from sim2real.envs.base import Env, EnvConfig, State
from sim2real.envs.registry import make, names

__all__ = ["Env", "EnvConfig", "State", "make", "names"]
