"""A sim2real env as a Gymnasium env: the batch stays on the JAX device, numpy at the boundary.

    from sim2real.interop.gymnasium import GymnasiumVectorEnv
    venv = GymnasiumVectorEnv("pendulum", num_envs=64, physics={"mass:pole": (0.5, 2.0)})
    obs, info = venv.reset(seed=0)                  # obs [64, O] float32 numpy
    obs, reward, terminated, truncated, info = venv.step(actions)   # actions [64, nu]

* Physics: ``physics={name: (low, high)}`` draws each env's physics uniformly from that box (the
  others at the env's defaults; checked like a training config's ``dr`` box: low < high, inside
  the physical bounds) at **every** reset, inside the jitted step (``envs/autoreset.py``),
  in the form SB3 / CleanRL code consumes (not run with them here); ``info["z"]`` holds the
  physics ``[N, P]`` of the step (names: ``venv.physics_names``).
* Actions are in actuator ctrl units (``action_space`` is the actuators' ctrlrange; the env clips
  to it), observations float32, unbounded.
* Auto-reset is Gymnasium's ``SAME_STEP`` mode: a finished env returns its first observation of
  the next episode; the last one is ``info["final_obs"]`` where ``info["_final_obs"]`` is true.
* ``reset(seed=s)`` is reproducible (the JAX key is ``s``); steps draw from the env's own key.

``GymnasiumEnv`` is the single-env view (what ``gymnasium.utils.env_checker.check_env`` checks).
"""
from __future__ import annotations

try:
    import gymnasium
    from gymnasium import spaces
    from gymnasium.vector import AutoresetMode
except ImportError as e:  # an optional dependency: say how to get it
    raise ImportError("sim2real.interop.gymnasium needs gymnasium (pip install 'gymnasium>=1.0')") from e

import jax
import jax.numpy as jnp
import numpy as np

from sim2real.envs import Env
from sim2real.envs.autoreset import step_autoreset
from sim2real.interop.physics import env_of as _env, sampler as _sampler


def _spaces(env: Env):
    obs = spaces.Box(-np.inf, np.inf, (env.obs_size,), np.float32)
    act = spaces.Box(env.ctrl_low, env.ctrl_high, (env.action_size,), np.float32)
    return obs, act


def _restart(adapter, seed: int | None):
    """Reset ``adapter`` (either class below): the JAX key from ``seed`` when given, else the next
    one; returns Gymnasium's ``(obs, info)``."""
    if seed is not None:
        adapter._key = jax.random.PRNGKey(int(seed))
    adapter._key, k = jax.random.split(adapter._key)
    adapter._state, adapter._z = adapter._reset(k)
    return np.asarray(adapter._state.obs, np.float32), {"z": np.asarray(adapter._z)}


def _actions(adapter, actions, shape: tuple[int, ...]) -> jax.Array:
    """Actions as a float32 array of ``shape``, refused (naming the shapes) when off or not finite."""
    if adapter._state is None:
        raise RuntimeError("call reset() before step()")
    a = np.asarray(actions, np.float32)
    if a.size != int(np.prod(shape)) or not np.isfinite(a).all():
        raise ValueError(f"actions: expected finite {list(shape)}, got {list(np.shape(actions))}"
                         + ("" if np.isfinite(a).all() else " with NaN/inf"))
    return jnp.asarray(a.reshape(shape))


class GymnasiumVectorEnv(gymnasium.vector.VectorEnv):
    """``num_envs`` copies of ``env`` (a name or an ``Env``) as one ``gymnasium.vector.VectorEnv``."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP}

    def __init__(self, env: Env | str, num_envs: int, physics: dict | None = None, **env_options):
        if int(num_envs) < 1:
            raise ValueError(f"num_envs={num_envs}: must be a positive integer")
        self.env = _env(env, **env_options)
        self.num_envs = int(num_envs)
        self.single_observation_space, self.single_action_space = _spaces(self.env)
        self.observation_space = gymnasium.vector.utils.batch_space(self.single_observation_space, self.num_envs)
        self.action_space = gymnasium.vector.utils.batch_space(self.single_action_space, self.num_envs)
        self.physics_names = list(self.env.spec.names)
        sample = _sampler(self.env, physics)
        env_ = self.env

        def reset(key):
            k_z, k_s = jax.random.split(key)
            z = jax.vmap(sample)(jax.random.split(k_z, self.num_envs))
            return jax.vmap(env_.reset)(jax.random.split(k_s, self.num_envs), z), z

        def step(state, z, action, key):
            keys = jax.random.split(key, self.num_envs)
            st, z2, tr, done = jax.vmap(lambda s, zz, a, k: step_autoreset(env_, s, zz, a, k, sample))(
                state, z, action, keys)
            return st, z2, tr, done

        self._reset, self._step = jax.jit(reset), jax.jit(step)
        self._state = self._z = None
        self._key = jax.random.PRNGKey(0)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        return _restart(self, seed)

    def step(self, actions):
        a = _actions(self, actions, (self.num_envs, self.env.action_size))
        self._key, k = jax.random.split(self._key)
        z = self._z
        self._state, self._z, tr, done = self._step(self._state, z, a, k)
        done = np.asarray(done)
        info = {"z": np.asarray(z), "final_obs": np.asarray(tr.next_obs, np.float32), "_final_obs": done}
        return (np.asarray(self._state.obs, np.float32), np.asarray(tr.reward, np.float64),
                np.asarray(tr.terminated), np.asarray(tr.truncated), info)


class GymnasiumEnv(gymnasium.Env):
    """One env (a name or an ``Env``) as a ``gymnasium.Env``; ``physics`` as for the vector env.
    The caller resets after an episode ends, as Gymnasium expects."""

    metadata = {"render_modes": []}

    def __init__(self, env: Env | str, physics: dict | None = None, **env_options):
        self.env = _env(env, **env_options)
        self.observation_space, self.action_space = _spaces(self.env)
        sample = _sampler(self.env, physics)
        env_ = self.env

        def reset(key):
            k_z, k_s = jax.random.split(key)
            z = sample(k_z)
            return env_.reset(k_s, z), z

        self._reset, self._step = jax.jit(reset), jax.jit(env_.step)
        self._state = self._z = None
        self._key = jax.random.PRNGKey(0)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        return _restart(self, seed)

    def step(self, action):
        self._state = self._step(self._state, _actions(self, action, (self.env.action_size,)), self._z)
        s = self._state
        info = {k: float(v) for k, v in s.metrics.items()}
        return (np.asarray(s.obs, np.float32), float(s.reward), bool(s.terminated), bool(s.truncated), info)
