"""A MuJoCo Playground task brought into sim2real: ``make("playground:CheetahRun")``.

The task's own ``MjModel`` is read into a :class:`~sim2real.physics.params.ParamSpec` (every moving
body's mass, the sliding friction of the geoms that touch, a multiplier on the actuated joints'
damping, every actuator's gain, gravity, action delay and observation noise), so uniform DR, LSDR,
EPOpt, ADR, DORAEMON, SimOpt and ES-MAML train on it like on a bundled env: the physics vector
``z [P]`` is an argument of ``reset``/``step`` and is redrawn at every reset inside jit.

How the physics reaches the task: Playground's ``reset``/``step`` read the model from
``self.mjx_model``, so each call runs on a shallow copy of the task whose ``_mjx_model`` is
``PhysicsModel.apply(z)``. The task's reward, termination and observation are its own, unchanged.
Auto-resets: Playground tasks settle their robot in ``reset`` (CheetahRun: 200 physics steps), and
sim2real's auto-reset computes a reset at every step for every env (``envs/autoreset.py``), which
would make each step ~200 times dearer. So an episode that *auto*-resets starts from one of
``reset_pool`` initial states (``make(name, reset_pool=N)``, default ``RESET_POOL``) of the task's
own reset computed once, on the nominal physics, at the first auto-reset, with its fresh physics ``z`` acting from its first step (Brax's auto-reset
likewise restarts from a stored first state). ``reset`` itself (the start of a rollout, every
evaluation episode) is the task's reset on the episode's own physics.

The action passes through sim2real's command path (the delay line) before the task sees it; effects
that act inside the physics substeps (Coulomb friction, motor lag, backlash) are not declared here,
because the task steps its substeps itself.

Needs the ``playground`` package (``pip install playground``); its JAX implementation of MJX is
used (``impl="jax"``), the one this package runs everywhere. Tasks whose observation is a dict, or
whose model needs downloaded assets (MuJoCo Menagerie robots) that are not present, are refused
when built.
"""
from __future__ import annotations

import copy
from typing import Any

import jax
import jax.numpy as jnp
import mujoco
from flax import struct

from sim2real.envs.base import MAX_STATE, Env, EnvConfig, State
from sim2real.physics import catalog
from sim2real.physics.params import Param, clip

PREFIX = "playground:"
RESET_POOL = 256  # initial states an auto-reset draws from


@struct.dataclass
class PlaygroundState(State):
    """sim2real's :class:`State` plus what the Playground task carries between steps.

    Attributes:
      info: the task's ``info`` dict (its PRNG key, counters, command ...).
      inner_obs: ``[O]`` the task's observation before observation noise (tasks may read it back).
    """

    info: Any = None
    inner_obs: Any = None


def _load(task: str):
    try:
        from mujoco_playground import registry
    except ImportError as e:
        raise ImportError("playground tasks need the 'playground' package: pip install playground "
                          f"(importing it failed: {e})") from None
    if task not in registry.ALL_ENVS:
        from sim2real.physics.params import UnknownNameError, unknown_name_message

        raise UnknownNameError(unknown_name_message("Playground task", task, sorted(registry.ALL_ENVS)))
    cfg = registry.get_default_config(task)
    if "impl" in cfg:
        cfg.impl = "jax"
    return registry.load(task, config=cfg), cfg


def env_class(name: str) -> type[Env]:
    """The env class of ``playground:<Task>`` (built once per task)."""
    if name not in _CLASSES:
        task = name[len(PREFIX):]
        inner, cfg = _load(task)
        episode = int(cfg.get("episode_length", 1000))
        _CLASSES[name] = type(f"Playground_{task}", (PlaygroundEnv,), {
            "name": name, "task": task, "_prototype": inner,
            "default_config": EnvConfig(episode_length=episode, frame_skip=1),
        })
    return _CLASSES[name]


_CLASSES: dict[str, type[Env]] = {}


class PlaygroundEnv(Env):
    """Base of the ``playground:<Task>`` envs (one subclass per task, made by :func:`env_class`).

    The control step and the physics step are the task's own (its ``ctrl_dt`` and ``sim_dt``), so
    ``env_options.frame_skip`` and ``timestep`` are refused; ``episode_length`` defaults to the task's.
    """

    task: str = ""
    _prototype: Any = None

    def __init__(self, config: EnvConfig | None = None, reset_pool: int = RESET_POOL, **overrides):
        if not (isinstance(reset_pool, int) and reset_pool >= 1):
            raise ValueError(f"env '{self.name}': reset_pool={reset_pool!r}; a positive integer")
        self.reset_pool, self._pool = reset_pool, None
        for k in ("frame_skip", "timestep"):
            if k in overrides:
                raise ValueError(f"env '{self.name}': env_options.{k} is the Playground task's own "
                                 "(its ctrl_dt and sim_dt); set it in the task's config instead")
        self.inner = self._prototype
        super().__init__(config, **overrides)
        key = jax.random.PRNGKey(0)
        shapes = jax.eval_shape(self.inner.reset, key)
        if not isinstance(shapes.obs, jax.ShapeDtypeStruct) or len(shapes.obs.shape) != 1:
            raise ValueError(f"env '{self.name}': the task's observation is "
                             f"{jax.tree_util.tree_map(lambda s: s.shape, shapes.obs)}; only a flat "
                             "array observation is supported")
        self._obs_size = int(shapes.obs.shape[0])
        self.metric_names = tuple(sorted(shapes.metrics))

    def load_model(self) -> mujoco.MjModel:
        m = copy.deepcopy(self.inner.mj_model)
        c = self.config
        if c.iterations is not None:
            m.opt.iterations = c.iterations
        if c.ls_iterations is not None:
            m.opt.ls_iterations = c.ls_iterations
        return m

    def declare_params(self, m: mujoco.MjModel) -> list[Param]:
        bodies = [b for b in range(1, m.nbody) if m.body_mass[b] > 0]
        touching = [g for g in range(m.ngeom) if m.geom_bodyid[g] > 0 and m.geom_contype[g] > 0]
        ps = []
        if touching:
            ps.append(Param("friction", float(m.geom_friction[touching[0], 0]), 0.0, 10.0, "-",
                            "sliding friction of every robot geom that collides", "geom_friction", -1))
        if len(self.joint_damping_dofs(m)):
            ps.append(Param("damping_scale", 1.0, 0.0, 100.0, "-",
                            "multiplier on the actuated joints' nominal damping", "joint_damping_scale"))
        ps += catalog.body_mass_params(m, bodies)
        ps += catalog.actuator_gain_params(m, range(m.nu))
        return ps

    @property
    def dt(self) -> float:
        return float(self.inner.dt)

    @property
    def obs_size(self) -> int:
        return self._obs_size

    def _task_on(self, model):
        """The Playground task reading ``model`` (an ``mjx.Model``) as its physics."""
        t = copy.copy(self.inner)
        t._mjx_model = model
        return t

    def _noisy(self, z, obs, key):
        std = z[self.spec.index("obs_noise")]
        return jnp.where(std > 0, obs + std * jax.random.normal(key, obs.shape), obs)

    def _metrics(self, inner_metrics, diverged):
        m = {k: jnp.asarray(inner_metrics[k], jnp.float32) for k in self.metric_names}
        return dict(m, diverged=diverged)

    def reset(self, key: jax.Array, z: jax.Array) -> PlaygroundState:
        """Initial state for physics ``z [P]`` (the task's own reset, on that physics)."""
        z = clip(self.spec, z)
        k_task, k_sense, k_next = jax.random.split(key, 3)
        s = self._task_on(self.physics.apply(z)).reset(k_task)
        zero = jnp.zeros(())
        return PlaygroundState(
            data=s.data, obs=self._noisy(z, s.obs, k_sense), reward=zero, terminated=jnp.zeros((), bool),
            truncated=jnp.zeros((), bool), effects=self.effects.init_state(), t=jnp.zeros((), jnp.int32),
            goal=jnp.zeros((0,)), key=k_next, metrics=self._metrics(s.metrics, zero), info=s.info,
            inner_obs=s.obs)

    def pool(self) -> PlaygroundState:
        """``[reset_pool]`` initial states of the task's reset on the nominal physics (made once)."""
        if self._pool is None:
            with jax.ensure_compile_time_eval():  # concrete even when first asked inside a trace
                keys = jax.random.split(jax.random.PRNGKey(0), self.reset_pool)
                self._pool = jax.jit(jax.vmap(self.reset, in_axes=(0, None)))(keys, jnp.asarray(self.default_z()))
        return self._pool

    def auto_reset(self, key: jax.Array, z: jax.Array) -> PlaygroundState:
        """A pooled initial state (nominal physics settled it) with fresh keys and observation noise."""
        z = clip(self.spec, z)
        k_pick, k_task, k_sense, k_next = jax.random.split(key, 4)
        pool = self.pool()
        s = jax.tree_util.tree_map(lambda x: x[jax.random.randint(k_pick, (), 0, self.reset_pool)], pool)
        info = dict(s.info, rng=k_task) if isinstance(s.info, dict) and "rng" in s.info else s.info
        return s.replace(obs=self._noisy(z, s.inner_obs, k_sense), key=k_next, info=info)

    def step(self, state: PlaygroundState, action: jax.Array, z: jax.Array) -> PlaygroundState:
        """One control step of the task under physics ``z [P]``; diverged physics as in ``Env.step``."""
        from mujoco_playground._src import mjx_env

        valid = self.spec_valid(z)
        z = clip(self.spec, z)
        ctrl = jnp.clip(action, self.ctrl_low, self.ctrl_high)
        es = self.effects.push(state.effects, ctrl)
        u, es = self.effects.actuate(z, es, 0, 1, state.data.qpos, self.dt, state.data.qvel)
        inner = mjx_env.State(state.data, state.inner_obs, state.reward, jnp.zeros(()),
                              {k: state.metrics[k] for k in self.metric_names}, state.info)
        s = self._task_on(self.physics.apply(z)).step(inner, u)
        d = s.data
        ok = (jnp.all(jnp.abs(d.qpos) < MAX_STATE) & jnp.all(jnp.abs(d.qvel) < MAX_STATE)
              & jnp.isfinite(d.qacc).all() & valid)
        data = jax.tree_util.tree_map(lambda new, old: jnp.where(ok, new, old), d, state.data)
        k_sense, k_next = jax.random.split(state.key)
        obs = jnp.where(ok, s.obs, state.inner_obs)
        terminated = (s.done > 0) | ~ok
        t = state.t + 1
        return state.replace(
            data=data, obs=self._noisy(z, obs, k_sense), reward=jnp.where(ok, s.reward, 0.0),
            terminated=terminated, truncated=(t >= self.config.episode_length) & ~terminated, effects=es,
            t=t, key=k_next, metrics=self._metrics(s.metrics, (~ok).astype(jnp.float32)), info=s.info,
            inner_obs=obs)

    # the hooks of Env that the task's own reset/step replace
    def init_qpos_qvel(self, key):
        raise NotImplementedError(f"env '{self.name}': the Playground task resets itself")

    def observe(self, qpos, qvel, goal):
        raise NotImplementedError(f"env '{self.name}': the Playground task observes itself")

    def task(self, data0, data, action, goal):
        raise NotImplementedError(f"env '{self.name}': the Playground task rewards itself")


def is_playground(name: str) -> bool:
    return isinstance(name, str) and name.startswith(PREFIX)


