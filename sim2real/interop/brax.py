"""A sim2real env as a Brax env, its physics redrawn at every reset inside jit.

    from brax.training.agents.ppo import train as ppo
    from sim2real.interop.brax import BraxEnv, wrap_for_training
    env = BraxEnv("hopper", physics={"mass:torso": (1.0, 9.0), "friction": (1.5, 2.5)})
    make_policy, params, metrics = ppo.train(env, num_timesteps=..., episode_length=1000,
                                             wrap_env_fn=wrap_for_training, ...)

Brax's own domain randomisation (``randomization_fn``) draws one physics per env slot when the
training wrapper is built and its ``AutoResetWrapper`` restores each slot's *first* state, so a
slot keeps its physics for the whole run (brax issue #446). Here a finished env gets a fresh
physics vector and a fresh initial state inside the jitted step: ``wrap_for_training`` is
Brax's ``envs.training.wrap`` (vmap, ``EpisodeWrapper``) with ``ResampleOnReset`` in place of
``AutoResetWrapper``; pass it as ``wrap_env_fn`` to Brax's PPO or SAC.

* Physics: ``physics={name: (low, high)}`` uniform (the others at the env's defaults; the box
  checked like a training config's ``dr`` box). ``state.pipeline_state.z`` is the physics ``[P]``
  the step ran under (names: ``env.env.spec.names``).
* Actions in ``[-1, 1]`` (Brax's policies squash to it), mapped linearly onto the actuators'
  ctrlrange. ``done`` is the env's termination (a fall, diverged physics); the time limit is
  Brax's ``EpisodeWrapper``'s ``episode_length``.
"""
from __future__ import annotations

try:
    from brax.envs import base as brax_base
    from brax.envs.wrappers.training import EpisodeWrapper, VmapWrapper
except ImportError as e:  # an optional dependency: say how to get it
    raise ImportError("sim2real.interop.brax needs brax (pip install 'brax>=0.12')") from e

import jax
import jax.numpy as jnp
from flax import struct

from sim2real.envs import Env
from sim2real.envs.base import State as EnvState
from sim2real.interop.physics import env_of, sampler


@struct.dataclass
class Physics:
    """Brax's ``pipeline_state`` of one env: the sim2real state and the physics ``z [P]`` it runs under."""
    state: EnvState
    z: jax.Array


class BraxEnv(brax_base.Env):
    """One sim2real env (a name or an ``Env``) as a ``brax.envs.Env``; Brax's wrappers batch it."""

    def __init__(self, env: Env | str, physics: dict | None = None, **env_options):
        self.env = env_of(env, **env_options)
        self._sample = sampler(self.env, physics)
        self._low = jnp.asarray(self.env.ctrl_low, jnp.float32)
        self._high = jnp.asarray(self.env.ctrl_high, jnp.float32)

    def reset(self, rng: jax.Array) -> brax_base.State:
        k_z, k_s = jax.random.split(rng)
        z = self._sample(k_z)
        st = self.env.reset(k_s, z)
        zero = jnp.zeros((), jnp.float32)
        return brax_base.State(pipeline_state=Physics(st, z), obs=st.obs, reward=zero, done=zero,
                               metrics={k: jnp.asarray(v, jnp.float32) for k, v in st.metrics.items()})

    def step(self, state: brax_base.State, action: jax.Array) -> brax_base.State:
        ctrl = self._low + (jnp.clip(action, -1.0, 1.0) + 1.0) * 0.5 * (self._high - self._low)
        ps = state.pipeline_state
        nxt = self.env.step(ps.state, ctrl, ps.z)
        metrics = dict(state.metrics)  # keys a wrapper added (Brax's EvalWrapper: reward) stay
        metrics.update({k: jnp.asarray(v, jnp.float32) for k, v in nxt.metrics.items()})
        return state.replace(pipeline_state=Physics(nxt, ps.z), obs=nxt.obs, reward=nxt.reward.astype(jnp.float32),
                             done=nxt.terminated.astype(jnp.float32), metrics=metrics)

    @property
    def observation_size(self) -> int:
        return self.env.obs_size

    @property
    def action_size(self) -> int:
        return self.env.action_size

    @property
    def backend(self) -> str:
        return "mjx"


class ResampleOnReset(brax_base.Wrapper):
    """Brax's ``AutoResetWrapper`` contract (a finished env returns the reward and ``done`` of its
    last step with the first observation of the next episode), but the next episode is a fresh
    reset of the batched env ``fresh`` -- new physics, new initial state -- not the slot's first."""

    def __init__(self, env: brax_base.Env, fresh: brax_base.Env):
        super().__init__(env)
        self._fresh = fresh

    def reset(self, rng: jax.Array) -> brax_base.State:  # rng [N, 2]
        state = self.env.reset(rng)
        state.info["reset_key"] = jax.vmap(lambda k: jax.random.fold_in(k, 1))(rng)
        return state

    def step(self, state: brax_base.State, action: jax.Array) -> brax_base.State:
        if "steps" in state.info:  # as Brax's wrapper: the episode counter restarts after a reset
            state.info["steps"] = jnp.where(state.done, jnp.zeros_like(state.info["steps"]), state.info["steps"])
        state = self.env.step(state.replace(done=jnp.zeros_like(state.done)), action)
        keys = jax.vmap(jax.random.split)(state.info["reset_key"])  # [N, 2, 2]
        fresh = self._fresh.reset(keys[:, 0])
        done = state.done.astype(bool)

        def pick(new, old):
            return jnp.where(done.reshape(done.shape + (1,) * (old.ndim - done.ndim)), new, old)

        state.info["reset_key"] = keys[:, 1]
        return state.replace(pipeline_state=jax.tree_util.tree_map(pick, fresh.pipeline_state, state.pipeline_state),
                             obs=pick(fresh.obs, state.obs))


def wrap_for_training(env: BraxEnv, episode_length: int = 1000, action_repeat: int = 1,
                      randomization_fn=None) -> brax_base.Wrapper:
    """Brax's training wrapper for a :class:`BraxEnv` (``wrap_env_fn`` of Brax's PPO / SAC)."""
    if randomization_fn is not None:
        raise ValueError("randomization_fn: BraxEnv draws its physics at every reset (BraxEnv(physics=...)); "
                         "Brax's randomization_fn would fix one physics per env slot")
    if not isinstance(env, BraxEnv):
        raise TypeError(f"wrap_for_training wraps a sim2real BraxEnv, got {type(env).__name__}")
    batched = VmapWrapper(env)
    return ResampleOnReset(EpisodeWrapper(batched, episode_length, action_repeat), batched)
