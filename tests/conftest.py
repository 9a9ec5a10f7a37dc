"""Shared fixtures: envs and one compiled batched rollout per env (JAX compiles are slow on CPU)."""
from __future__ import annotations

import functools
import os
import tempfile


import jax  # noqa: E402

# identical programs compiled again (each train() builds fresh closures) come from disk; a fresh
# folder per session, so nothing compiled on another machine is ever loaded. The commands run as
# subprocesses use it too (common/compile_cache.py) instead of the user's ~/.cache.
_CACHE = tempfile.mkdtemp(prefix="sim2real-jax-cache-")
jax.config.update("jax_compilation_cache_dir", _CACHE)
os.environ["SIM2REAL_COMPILE_CACHE"] = _CACHE
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.5)
# Most tests spend their time compiling (a PPO update, a training chunk, a batched rollout) and
# run the result briefly: they compile with most of XLA's optimisations off, which compiles 2-3x
# faster (the SimOpt script test: 168 s -> 68 s; the suite 2145 s -> 1382 s on 2 cores). The
# program is the same; only LLVM's work on it (vectorisation, unrolling) differs, so results
# differ by rounding alone. Tests whose
# time is spent running -- the diagnosis' thousands of simulated segments, PPO to a learned
# swing-up -- would run 2x slower that way, and those that check a learning outcome are
# sensitive to rounding: they are marked ``optimized`` and compile as users do. Subprocesses
# (the multi-process driver test) read the same setting from the environment.
os.environ.setdefault("JAX_DISABLE_MOST_OPTIMIZATIONS", "1")
FAST_COMPILE = os.environ["JAX_DISABLE_MOST_OPTIMIZATIONS"] == "1"
jax.config.update("jax_disable_most_optimizations", FAST_COMPILE)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import sim2real  # noqa: E402,F401
from sim2real.envs import make  # noqa: E402


# the learned-randomisation toy: 2 Nm hold a light pole upright but not a heavy one (ADR, DORAEMON)
BALANCE = ["env=pendulum_balance", "ppo.num_envs=64", "ppo.num_steps=64", "ppo.gamma=0.98", "ppo.lr=1e-3",
           "ppo.reward_scale=0.1", "ppo.net.hidden=[64,64]", "dr.params=[mass:pole]", "dr.low=[0.2]", "dr.high=[3.0]"]


@pytest.fixture(autouse=True)
def _xla_optimisations(request):
    """``@pytest.mark.optimized`` tests compile with XLA's full optimisations (see above)."""
    if FAST_COMPILE and request.node.get_closest_marker("optimized") is not None:
        jax.config.update("jax_disable_most_optimizations", False)
        yield
        jax.config.update("jax_disable_most_optimizations", True)
    else:
        yield


@functools.lru_cache(maxsize=None)
def env_for(name: str):
    return make(name)


@functools.lru_cache(maxsize=None)
def batched_rollout(name: str):
    """jit(vmap over z) of a T-step rollout with fixed actions, returning per-step arrays."""
    env = env_for(name)

    def one(z, actions, key):
        s = env.reset(key, z)

        def f(s, a):
            s = env.step(s, a, z)
            out = dict(qpos=s.data.qpos, qvel=s.data.qvel, obs=s.obs, reward=s.reward,
                       terminated=s.terminated, truncated=s.truncated,
                       diverged=s.metrics["diverged"], force=s.data.actuator_force)
            return s, out

        return jax.lax.scan(f, s, actions)[1]

    return jax.jit(jax.vmap(one, in_axes=(0, None, None)))


T_ROLLOUT = 40


def batch_size(name: str) -> int:
    """One batch size per env (default, modified, each parameter at both bounds, all-low, all-high)."""
    return 4 + 2 * len(env_for(name).spec)


def run_rows(name: str, zs, key=None):
    """Run rows ``zs [N, P]`` for ``T_ROLLOUT`` steps of the env's standard actions.

    Pads to the env's fixed batch size so every test of an env reuses one compiled rollout.
    Returns a dict of numpy arrays ``[N, T, ...]``.
    """
    env = env_for(name)
    zs = np.asarray(zs, np.float32)
    n, full = len(zs), batch_size(name)
    assert n <= full
    padded = np.concatenate([zs, np.tile(env.default_z(), (full - n, 1))])
    key = jax.random.PRNGKey(0) if key is None else key
    out = batched_rollout(name)(jnp.asarray(padded), smooth_actions(env, T_ROLLOUT), key)
    return {k: np.asarray(v)[:n] for k, v in out.items()}


def smooth_actions(env, T, seed=0, scale=0.5):
    """Smooth random actions ``[T, A]`` inside the ctrl range."""
    rng = np.random.default_rng(seed)
    a = np.clip(np.cumsum(rng.normal(0, scale, (T, env.action_size)), 0), -1, 1)
    lo = np.where(np.isfinite(env.ctrl_low), env.ctrl_low, -1.0)
    hi = np.where(np.isfinite(env.ctrl_high), env.ctrl_high, 1.0)
    return jnp.asarray(lo + (a + 1) / 2 * (hi - lo), jnp.float32)


@pytest.fixture
def key():
    return jax.random.PRNGKey(0)
