"""Env base: MJX physics with the physics vector passed in, gymnax-style.

``reset(key, z) -> State`` and ``step(state, action, z) -> State``; ``self`` holds only static
structure (compiled model, index arrays, parameter spec), so ``vmap(env.step)`` over envs with
different ``z`` is one trace and changing ``z`` never recompiles (``tests/test_envs.py`` counts
traces).

Conventions:
  * ``action [nu]`` is in actuator ctrl units and is clipped to ``ctrlrange``.
  * ``terminated`` (task failure or diverged physics) and ``truncated`` (time limit) are kept apart.
  * NaN/inf (or a state beyond ``MAX_STATE``) after a step terminates that env, keeps its last
    finite state and is counted in ``metrics['diverged']``: nothing non-finite leaves ``step``.
  * Observations are functions of joint positions/velocities only, so ``reset`` needs no
    forward pass (cheap inside an auto-reset that runs every step).
"""
from __future__ import annotations

import dataclasses
import os
from typing import Any

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from flax import struct
from sim2real._mjx import mjx

from sim2real.common import config as config_lib
from sim2real.physics import catalog, stepper
from sim2real.physics.effects import EffectState
from sim2real.physics.kinds.base import ctrl_limits
from sim2real.physics.params import Param, clip, in_bounds
from sim2real.physics.plant import Plant

ASSETS = os.path.join(os.path.dirname(__file__), "assets")
# A state entry beyond this counts as diverged (NaN/inf fail the comparison too): far past any
# real motion of these robots, and small enough that rewards built from squares stay finite.
MAX_STATE = 1e6


@struct.dataclass
class State:
    """One env's state (add a leading batch axis under vmap).

    Attributes:
      data: ``mjx.Data``.
      obs: ``[O]`` observation after the last step / reset (with sensor effects and noise).
      reward: ``[]`` reward of the last step.
      terminated: ``[]`` bool, task failure or diverged physics.
      truncated: ``[]`` bool, time limit reached (bootstrap the value here).
      effects: effect memory (delay buffer, motor lag, backlash gap).
      t: ``[]`` int32 control steps since reset.
      goal: ``[G]`` task variables drawn at reset (a target), empty for most envs.
      key: PRNG key for per-step noise.
      metrics: dict of ``[]`` floats, env-specific plus ``diverged``.
    """

    data: mjx.Data
    obs: jax.Array
    reward: jax.Array
    terminated: jax.Array
    truncated: jax.Array
    effects: EffectState
    t: jax.Array
    goal: jax.Array
    key: jax.Array
    metrics: dict[str, jax.Array]


OUT_OF_BOUNDS = ("clip", "terminate")


@dataclasses.dataclass(frozen=True)
class EnvConfig:
    """Static env settings (any of them can be overridden in ``make(name, **overrides)``).

    Attributes:
      episode_length: control steps before truncation.
      frame_skip: physics substeps per control step.
      timestep: physics timestep in seconds (None: the XML's).
      iterations: constraint solver iterations (None: the XML's).
      ls_iterations: solver line-search iterations (None: the XML's).
      max_delay: length of the action-delay buffer in control steps.
      coulomb_eps: velocity scale of the smooth Coulomb friction model.
      out_of_bounds: what a physics vector outside the parameters' physical bounds does inside
        ``jit``: ``clip`` (simulate the nearest bound; the default) or ``terminate`` (the robot
        cannot exist: the episode ends at its first step with reward 0 and counts as diverged,
        as negative masses or sizes did in the simulator of the LSDR paper).
    """

    episode_length: int = 1000
    frame_skip: int = 1
    timestep: float | None = None
    iterations: int | None = None
    ls_iterations: int | None = None
    max_delay: int = 4
    coulomb_eps: float = 1e-3
    out_of_bounds: str = "clip"


class Env:
    """Base class; subclasses set ``xml`` and implement the hooks at the bottom."""

    name: str = "base"
    xml: str = ""
    default_config = EnvConfig()
    metric_names: tuple[str, ...] = ()

    def __init__(self, config: EnvConfig | None = None, **overrides):
        cfg = config or self.default_config
        # typed like every config (env_options of a training config land here): an unknown key
        # gets a "did you mean", a value of the wrong type names its key
        given = config_lib.from_dict(EnvConfig, overrides, "env_options.")
        self.config = dataclasses.replace(cfg, **{k: getattr(given, k) for k in overrides})
        if self.config.out_of_bounds not in OUT_OF_BOUNDS:
            raise ValueError(f"env '{self.name}': out_of_bounds={self.config.out_of_bounds!r}; "
                             f"choose one of {list(OUT_OF_BOUNDS)}")
        m = self.load_model()
        # the plant the diagnosis fits too (physics/plant.py); its parts under the names envs use
        self.plant = Plant(m, self.declare_params(m), self.config.max_delay, self.config.coulomb_eps,
                           self.joint_damping_dofs(m))
        self.spec, self.physics, self.effects = self.plant.spec, self.plant.physics, self.plant.effects
        self.mj_model = self.plant.mj  # the model MJX runs (saturation clamps added), for parity
        self._data0 = self.plant.data0
        m = self.mj_model
        self.ctrl_low, self.ctrl_high = (x.astype(np.float32) for x in ctrl_limits(m))

    # ---------------------------------------------------------------- model loading ----
    def load_model(self) -> mujoco.MjModel:
        m = mujoco.MjModel.from_xml_path(os.path.join(ASSETS, self.xml))
        c = self.config
        if c.timestep is not None:
            m.opt.timestep = c.timestep
        if c.iterations is not None:
            m.opt.iterations = c.iterations
        if c.ls_iterations is not None:
            m.opt.ls_iterations = c.ls_iterations
        if m.opt.integrator != mujoco.mjtIntegrator.mjINT_EULER or (
            m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_EULERDAMP
        ):
            raise ValueError(f"{self.xml}: envs use the Euler integrator with implicit damping "
                             "(Coulomb friction relies on it)")
        return m

    # ---------------------------------------------------------------------- sizes ------
    @property
    def dt(self) -> float:
        return float(self.mj_model.opt.timestep) * self.config.frame_skip

    @property
    def action_size(self) -> int:
        return int(self.mj_model.nu)

    @property
    def obs_size(self) -> int:
        goal = self.init_goal(jax.random.PRNGKey(0))
        return int(self.observe(jnp.asarray(self.mj_model.qpos0), jnp.zeros(self.mj_model.nv), goal).shape[-1])

    def default_z(self) -> np.ndarray:
        return self.spec.default.copy()

    def z_of(self, **values) -> np.ndarray:
        """Full physics vector from named values (validated against the bounds)."""
        return self.spec.vector(values)

    def check_z(self, z) -> None:
        """Raise if a concrete ``z`` has the wrong shape, is non-finite or out of bounds."""
        self.spec.validate(z, where=f"z for env '{self.name}'")

    # ------------------------------------------------------------------------ API ------
    def reset(self, key: jax.Array, z: jax.Array) -> State:
        """Initial state for physics ``z [P]``."""
        z = clip(self.spec, z)
        k_init, k_goal, k_sense, k_next = jax.random.split(key, 4)
        qpos, qvel = self.init_qpos_qvel(k_init)
        goal = self.init_goal(k_goal)
        data = self._data0.replace(qpos=qpos, qvel=qvel)
        obs = self._observe(z, data, goal, k_sense)
        zero = jnp.zeros(())
        return State(
            data=data, obs=obs, reward=zero, terminated=jnp.zeros((), bool), truncated=jnp.zeros((), bool),
            effects=self.effects.init_state(), t=jnp.zeros((), jnp.int32), goal=goal, key=k_next,
            metrics={k: zero for k in self.metric_names + ("diverged",)},
        )

    def auto_reset(self, key: jax.Array, z: jax.Array) -> State:
        """The reset an auto-reset computes at *every* step for every env (``envs/autoreset.py``)
        and keeps where an episode ended: ``reset`` here, because it is cheap. An env whose reset
        is expensive (a Playground task settles for 200 physics steps) overrides it."""
        return self.reset(key, z)

    def step(self, state: State, action: jax.Array, z: jax.Array) -> State:
        """Advance one control step (``frame_skip`` physics steps) under physics ``z [P]``."""
        valid = self.spec_valid(z)
        z = clip(self.spec, z)
        model = self.physics.apply(z)
        data0 = state.data
        ctrl = jnp.clip(action, self.ctrl_low, self.ctrl_high)
        data, eff = stepper.advance(self.effects, model, z, data0, state.effects, ctrl, self.dt,
                                    self.config.frame_skip)

        ok = (jnp.all(jnp.abs(data.qpos) < MAX_STATE) & jnp.all(jnp.abs(data.qvel) < MAX_STATE)
              & jnp.isfinite(data.qacc).all() & valid)
        data = jax.tree_util.tree_map(lambda new, old: jnp.where(ok, new, old), data, data0)
        k_sense, k_next = jax.random.split(state.key)
        obs = self._observe(z, data, state.goal, k_sense)
        reward, terminated, metrics = self.task(data0, data, action, state.goal)
        t = state.t + 1
        metrics = dict(metrics, diverged=(~ok).astype(jnp.float32))
        return state.replace(
            data=data, obs=obs, reward=jnp.where(ok, reward, 0.0),
            terminated=terminated | ~ok, truncated=(t >= self.config.episode_length) & ok & ~terminated,
            effects=eff, t=t, key=k_next, metrics=metrics,
        )

    def spec_valid(self, z: jax.Array) -> jax.Array:
        """``[]`` bool: False only when ``out_of_bounds='terminate'`` and ``z`` leaves the bounds."""
        if self.config.out_of_bounds == "clip":
            return jnp.ones((), bool)
        return in_bounds(self.spec, z)

    def _observe(self, z, data, goal, key):
        k1, k2 = jax.random.split(key)
        qpos = self.effects.sense(z, data.qpos, k1)
        obs = self.observe(qpos, data.qvel, goal)
        if "obs_noise" in self.spec:
            std = z[self.spec.index("obs_noise")]
            obs = jnp.where(std > 0, obs + std * jax.random.normal(k2, obs.shape), obs)
        return obs

    # ---------------------------------------------------------------------- hooks ------
    def declare_params(self, m: mujoco.MjModel) -> list[Param]:
        """Nominal + effect parameters of this env (``common_params`` are appended)."""
        raise NotImplementedError

    def joint_damping_dofs(self, m: mujoco.MjModel) -> list[int]:
        """Dofs the global ``joint_damping`` parameter sets (default: actuated joints)."""
        return [int(m.jnt_dofadr[j]) for j in catalog.actuated_joints(m)]

    def init_qpos_qvel(self, key) -> tuple[jax.Array, jax.Array]:
        raise NotImplementedError

    def init_goal(self, key) -> jax.Array:
        """Task variables drawn at reset (default: none)."""
        return jnp.zeros((0,))

    def observe(self, qpos: jax.Array, qvel: jax.Array, goal: jax.Array) -> jax.Array:
        raise NotImplementedError

    def task(self, data0: mjx.Data, data: mjx.Data, action: jax.Array,
             goal: jax.Array) -> tuple[jax.Array, jax.Array, dict[str, Any]]:
        """``(reward [], terminated [] bool, metrics)`` of the transition data0 -> data."""
        raise NotImplementedError
