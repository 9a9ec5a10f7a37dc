"""What every outer-loop algorithm shares: the DR box config and the PPO it trains."""
from __future__ import annotations

import dataclasses
from typing import Any, Literal

import jax.numpy as jnp
import numpy as np

from sim2real.envs.base import Env
from sim2real.physics.params import Subspace, bounds_text

DiagnosisBox = Literal["std", "span", "centred"]  # how a diagnosis' box is drawn (``from_diagnosis.box``)


@dataclasses.dataclass(frozen=True)
class DRConfig:
    """Which physics parameters are randomised, over which box, and fixed values for the rest.

    Attributes:
      params: names of randomised parameters (empty: fixed physics).
      low, high: box bounds, one per name (may reach past the physical bounds: values are
        clipped to them in the simulator, see README "bounds rule").
      fixed: name -> value for parameters held at a non-default value.
      from_diagnosis: a diagnosis folder of the env's own model: its fitted physics becomes the
        env's, randomised over +- ``diagnosis_k`` std (``algos/from_diagnosis.py``; resolved into
        ``params``/``low``/``high``/``fixed`` when training starts).
      diagnosis_k: half-width of that box in standard deviations of the fit.
      diagnosis_box: ``std``: the box is ``value +- k std``; ``span``: it also reaches back to the
        env's own (nominal) value, so training sees the model it had as well as the one found;
        ``centred``: as far past the value as back to the env's own (``from_diagnosis.box``).
    """

    params: tuple[str, ...] = ()
    low: tuple[float, ...] = ()
    high: tuple[float, ...] = ()
    fixed: dict[str, float] = dataclasses.field(default_factory=dict)
    from_diagnosis: str = ""
    diagnosis_k: float = 2.0
    diagnosis_box: DiagnosisBox = "std"


class DRSpace:
    """The randomised sub-vector: ``expand(z_sub [K]) -> z [P]`` on top of the fixed base.

    ``key``: the config key the box came from, named in errors (``dr``; the loop's ``fallback``)."""

    def __init__(self, env: Env, cfg: DRConfig, key: str = "dr"):
        if not (len(cfg.params) == len(cfg.low) == len(cfg.high)):
            raise ValueError(f"{key}.params, {key}.low and {key}.high must have the same length "
                             f"(got {len(cfg.params)}, {len(cfg.low)}, {len(cfg.high)})")
        self.env = env
        self.sub = Subspace(env.spec, tuple(cfg.params))  # (unknown names: an error listing the known ones)
        outside_ok = env.config.out_of_bounds == "terminate"
        for n, lo, hi in zip(cfg.params, cfg.low, cfg.high):
            if not (np.isfinite(lo) and np.isfinite(hi)):
                raise ValueError(f"{key} box for '{n}': [{lo}, {hi}] must be finite")
            if not lo < hi:
                raise ValueError(f"{key} box for '{n}': low {lo} must be below high {hi}")
            p = env.spec[n]
            if not outside_ok and (lo < p.low or hi > p.high):
                # the bounds rule (physics/params.py): a box is given at the API boundary, so it is
                # checked, not clipped; a box that means to reach past the bounds (the LSDR paper's
                # priors) says so with out_of_bounds=terminate, where impossible contexts end at once
                raise ValueError(f"{key} box for '{n}' [{lo}, {hi}] reaches outside its physical bounds "
                                 f"{bounds_text(p)}; keep it inside, or set "
                                 "env_options.out_of_bounds=terminate (impossible contexts end their episode)")
        self.base = env.z_of(**{k: float(v) for k, v in cfg.fixed.items()})
        self.low = np.asarray(cfg.low, np.float32)
        self.high = np.asarray(cfg.high, np.float32)

    def __len__(self) -> int:
        return len(self.sub)

    def expand(self, z_sub):
        return self.sub.expand(z_sub, self.base)

    @property
    def names(self) -> tuple[str, ...]:
        return self.sub.names

    def start_box(self, init_low=(), init_high=(), key: str = "algo_options.init_low/init_high"):
        """``(low [K], high [K])`` where a learned distribution starts inside this (limit) box: the
        given box, or the env's nominal value of each parameter (a point, clipped into the box)."""
        if not len(init_low) and not len(init_high):
            nominal = np.asarray([self.env.spec[n].default for n in self.names], np.float32)
            nominal = np.clip(nominal, self.low, self.high)
            return nominal, nominal.copy()
        lo, hi = np.asarray(init_low, np.float32), np.asarray(init_high, np.float32)
        if lo.shape != (len(self),) or hi.shape != (len(self),):
            raise ValueError(f"{key}: one value per dr.params entry ({len(self)}), got {len(lo)} and {len(hi)}")
        for n, a, b, la, lb in zip(self.names, lo, hi, self.low, self.high):
            if not (la <= a <= b <= lb):
                raise ValueError(f"{key} for '{n}': [{a:g}, {b:g}] must be an ordered box inside the limit box "
                                 f"dr.low..dr.high [{la:g}, {lb:g}]")
        return lo, hi


class OuterLoop:
    """The contract between an outer-loop algorithm and the training driver (``train.py``).

    The driver calls only what is declared here, jitted and vmapped over seeds; an algorithm
    subclasses this, sets ``env``, ``ppo`` (a :class:`~sim2real.rl.ppo.PPO`) and ``space`` (its
    :class:`DRSpace`: the box and the base physics) and implements the first three methods. The defaults say what an algorithm that does not override them gets.

    Attributes:
      takes_update_index: ``update`` is called as ``update(state, i)`` with the unbatched update
        index (an algorithm that acts every n-th update branches on it with a real ``lax.cond``).
      warm_start_from: a finished run folder whose policy starts this algorithm (set from the
        algorithm's options); the driver reads it and calls :meth:`start_from` -- reading run
        folders is the driver's, so no algorithm imports it.
      warm_start_seed: which seed of that run starts every seed here (-1: all of them, one per
        seed here, or its only one).
      warm_std: the action standard deviation that policy restarts from (0: its own; set from
        options that offer it, UDR's ``warm_std``).
      warm: ``(params [S, ...], obs_stats [S, ...])`` of that policy once :meth:`start_from` ran
        (None otherwise); the algorithm's ``init_seeds`` starts from it.
      adapts: the algorithm meta-learns a policy that adapts to given physics (:meth:`adapt`;
        ES-MAML): ``scripts/evaluate.py adapt=true`` evaluates it after adaptation.
    """

    takes_update_index: bool = False
    warm_start_from: str = ""
    warm_start_seed: int = -1
    warm_std: float = 0.0
    warm: Any = None
    adapts: bool = False

    def init(self, key) -> Any:
        """One seed's state from a PRNG key."""
        raise NotImplementedError

    def update(self, state, i=None) -> tuple[Any, dict[str, Any]]:
        """``(state, metrics)`` after one update (metrics: scalars or per-episode arrays)."""
        raise NotImplementedError

    def policy(self, state) -> tuple[Any, Any]:
        """``(network params, observation statistics)``: what evaluation and export use."""
        raise NotImplementedError

    def init_seeds(self, keys) -> Any:
        """States for every seed ``keys [S, 2]`` (default: ``init`` vmapped)."""
        import jax

        return jax.vmap(self.init)(keys)

    def env_steps_per_update(self) -> int:
        """Env steps per seed in one ``update`` (default: one PPO batch)."""
        return int(self.ppo.cfg.batch_size)

    def total_updates(self, total_steps: int, done: int) -> int:
        """Updates in the whole run, given the config's ``total_steps`` per seed and the updates
        ``done`` before this call (a resumed run). Default: as many as ``total_steps`` buys; an
        algorithm that counts its own iterations (SimOpt) says so here."""
        return max(1, total_steps // self.env_steps_per_update())

    def adapt(self, params, obs_stats, z, key) -> tuple[Any, Any, Any]:
        """Few-shot adaptation of one seed's policy to physics ``z [P]``: ``(params, obs_stats,
        train_return)``; only algorithms with ``adapts`` implement it."""
        raise NotImplementedError(f"{type(self).__name__} does not adapt")

    def start_from(self, params, obs_stats, num_seeds: int) -> None:
        """Keep a finished run's policy (``[1 or num_seeds, ...]``; the driver checked its env,
        network and seed count) as ``warm``, one copy per seed; only algorithms that set
        ``warm_start_from`` are asked, and their ``init_seeds`` uses it."""
        import jax
        import jax.numpy as jnp

        n = jax.tree_util.tree_leaves(params)[0].shape[0]
        tile = lambda x: jnp.repeat(jnp.asarray(x), num_seeds // n, axis=0)  # noqa: E731
        self.warm = jax.tree_util.tree_map(tile, (params, obs_stats))

    def warm_ppo(self, ppo_state):
        """``ppo_state`` (every seed's) with the warm start's policy in it (its action standard
        deviation ``warm_std`` where that is set), or as it is without one."""
        if self.warm is None:
            return ppo_state
        params, obs_stats = self.warm
        if self.warm_std > 0:
            log_std = jnp.full_like(params["params"]["log_std"], jnp.log(self.warm_std))
            params = {**params, "params": {**params["params"], "log_std": log_std}}
        return ppo_state.replace(params=params, obs_stats=obs_stats)


def metrics_mean(m: dict[str, Any]) -> dict[str, Any]:
    return {k: jnp.mean(v) for k, v in m.items()}
