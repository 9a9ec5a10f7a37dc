"""ES-MAML (Song et al. 2020) with a PPO inner loop (seed 004).

Meta-parameters theta are the policy's weights. One meta-iteration, a single jitted function:

1. evosax's OpenES asks for a population ``theta + sigma * g_i`` with antithetic pairs ``+-g_i``,
2. every member gets a task (physics ``z ~ U(box)``; both members of a pair get the same task, which
   cancels the task's own difficulty out of the pair's difference) and adapts to it with
   ``inner_updates`` PPO updates (seed 004: 3 x 4096 env steps) — the adaptation operator U,
3. fitness = return of the adapted policy on its task (deterministic episodes),
4. OpenES turns the centred-rank fitnesses into the estimate
   ``grad ≈ 1/(N sigma) sum_i f(U(theta + sigma g_i)) g_i`` and takes an Adam step.

Population, tasks and inner loops run in parallel under ``vmap``; the meta step ``vmap``s over seeds.
Observation normalisation: each inner loop starts from the meta statistics and updates its own;
the meta statistics become the population average of the adapted ones (so they track the states
the adapted policies visit).

Evaluation with few-shot adaptation (:meth:`ESMAML.adapt_and_evaluate`) runs the same U on the
test physics before the deterministic test episodes.
"""
from __future__ import annotations

import dataclasses

import jax
import jax.flatten_util
import jax.numpy as jnp
import optax
from flax import struct

from sim2real.algos.base import DRConfig, DRSpace, OuterLoop
from sim2real.algos.registry import register
from sim2real.envs import parallel
from sim2real.envs.base import Env
from sim2real.rl.episodes import episodes, with_horizon
from sim2real.rl import networks, normalize
from sim2real.rl.ppo import PPO, PPOConfig, PPOState
from sim2real.rl.rollout import init_runner


@dataclasses.dataclass(frozen=True)
class ESMAMLConfig:
    """ES-MAML settings.

    Attributes:
      population: ES population (even: antithetic pairs).
      sigma: perturbation standard deviation in weight space.
      meta_lr: Adam step size on theta.
      inner_updates: PPO updates of the adaptation operator (seed 004: 3).
      eval_episodes: deterministic episodes that score an adapted member.
      eval_horizon: steps of those episodes (0: the env's episode length).
      warm_start: a training run folder whose ``policy.msgpack`` (same env and network) gives the
        initial meta-parameters and observation statistics, one per seed or one for all seeds
        (seed 004's budget-scaled runs start from a uniform-DR policy); empty: random init.
    """

    population: int = 32
    sigma: float = 0.02
    meta_lr: float = 0.01
    inner_updates: int = 3
    eval_episodes: int = 1
    eval_horizon: int = 0
    warm_start: str = ""


@struct.dataclass
class ESMAMLState:
    es: object                      # evosax OpenES state (mean = flat theta)
    obs_stats: normalize.RunningStats
    key: jax.Array
    step: jax.Array


class ESMAML(OuterLoop):
    """Static pieces; ``init(key)``, ``update(state) -> (state, metrics)``, ``adapt_and_evaluate``."""

    def __init__(self, env: Env, ppo_cfg: PPOConfig, dr: DRConfig, cfg: ESMAMLConfig):
        if cfg.population < 2 or cfg.population % 2:
            raise ValueError(f"es_maml population must be even and >= 2 (antithetic pairs), got {cfg.population}")
        if cfg.sigma <= 0 or cfg.inner_updates < 0:
            raise ValueError("es_maml needs sigma > 0 and inner_updates >= 0")
        if ppo_cfg.net.kind != "mlp" or ppo_cfg.net.use_context:
            raise ValueError("ES-MAML meta-learns a plain MLP policy (ppo.net.kind=mlp, use_context=false)")
        self.env, self.cfg = env, cfg
        self.space = DRSpace(env, dr)
        # the inner loop's step size is part of U and must not decay with the meta-iterations
        self.ppo = PPO(env, dataclasses.replace(ppo_cfg, anneal_lr=False, split_envs=False, data_parallel=False), 1)
        # with ppo.split_envs / data_parallel the population is split over the host's devices,
        # each member's inner loop whole on one device (members are independent: no communication)
        self.spreads = ppo_cfg.spreads
        if self.spreads:  # before any trace (the multi-GPU partitioner setting, envs/parallel.py)
            parallel.batch_devices(cfg.population)
        self.horizon = cfg.eval_horizon or env.config.episode_length
        self.eval_env = with_horizon(env, self.horizon)
        _, template = networks.init_params(jax.random.PRNGKey(0), ppo_cfg.net, env.obs_size, 0, env.action_size)
        # (imported here: importing evosax.algorithms starts JAX's backends, after which the CPU
        # device count that ppo.split_envs / data_parallel ask for can no longer be set)
        from evosax.algorithms import Open_ES

        self.es = Open_ES(population_size=cfg.population, solution=template, use_antithetic_sampling=True,
                          optimizer=optax.adam(cfg.meta_lr), std_schedule=optax.constant_schedule(cfg.sigma))
        self.es_params = self.es.default_params

    # ----------------------------------------------------------------------------------------
    def sample_task(self, key):
        if not len(self.space):
            return jnp.asarray(self.space.base)
        u = jax.random.uniform(key, (len(self.space),), minval=self.space.low, maxval=self.space.high)
        return self.space.expand(u)

    def init(self, key, params=None, obs_stats=None) -> ESMAMLState:
        """Fresh meta-parameters, or warm-started from a trained policy's ``params``/``obs_stats``."""
        k_net, k_es, k_next = jax.random.split(key, 3)
        if params is None:
            _, params = networks.init_params(k_net, self.ppo.cfg.net, self.env.obs_size, 0, self.env.action_size)
        stats = normalize.init(self.env.obs_size) if obs_stats is None else obs_stats
        return ESMAMLState(self.es.init(k_es, params, self.es_params), stats, k_next, jnp.zeros((), jnp.int32))

    def init_seeds(self, keys):
        """``init`` for every seed's key ``[S, 2]``, from the warm start when one is loaded."""
        if self.warm is None:
            return jax.vmap(self.init)(keys)
        return jax.vmap(self.init)(keys, *self.warm)

    def theta(self, st: ESMAMLState):
        """Meta-parameters as the network's pytree (with the state's leading seed axes, if any)."""
        if st.es.mean.ndim > 1:  # the driver exports the policies of all seeds at once
            return jax.vmap(self.theta)(st)
        return self.es.get_mean(st.es)

    # ------------------------------------------------------------------- adaptation U ----
    adapts = True

    def adapt(self, params, obs_stats, z, key):
        """``inner_updates`` PPO updates on fixed physics ``z [P]`` from ``params``.

        Returns ``(params, obs_stats, train_return)`` of the adapted policy.
        """
        k_run, k_ppo = jax.random.split(key)
        sample = lambda k: z
        runner = init_runner(self.env, k_run, self.ppo.cfg.num_envs, sample, 0)
        st = PPOState(params, self.ppo.tx.init(params), obs_stats, runner, k_ppo, jnp.zeros((), jnp.int32))
        if self.cfg.inner_updates == 0:
            return params, obs_stats, jnp.zeros(())
        st, m = jax.lax.scan(lambda s, _: self.ppo.update(s, sample), st, None, length=self.cfg.inner_updates)
        return st.params, st.obs_stats, m["episode_return"][-1]

    def evaluate(self, params, obs_stats, z, key):
        """Mean return of ``eval_episodes`` deterministic episodes on ``z``."""
        return episodes(self.eval_env, self.ppo, params, obs_stats, z[None], key, self.cfg.eval_episodes)["return"].mean()

    def adapt_and_evaluate(self, params, obs_stats, z, key):
        """Few-shot adaptation to ``z`` then evaluation: ``(return_after, return_before)``."""
        k_a, k_e = jax.random.split(key)
        before = self.evaluate(params, obs_stats, z, k_e)
        p2, s2, _ = self.adapt(params, obs_stats, z, k_a)
        return self.evaluate(p2, s2, z, k_e), before

    # ------------------------------------------------------------------ meta iteration ----
    def update(self, st: ESMAMLState):
        """One meta-iteration (whole population with its inner PPO loops). Returns ``(state, metrics)``."""
        cfg = self.cfg
        key, k_ask, k_task, k_inner, k_tell = jax.random.split(st.key, 5)
        pop, es_state = self.es.ask(k_ask, st.es, self.es_params)
        half = cfg.population // 2
        tasks = jax.vmap(self.sample_task)(jax.random.split(k_task, half))
        tasks = jnp.concatenate([tasks, tasks])            # antithetic partners share a task
        keys = jax.random.split(k_inner, half)
        keys = jnp.concatenate([keys, keys])               # ... and their random streams

        def member(obs_stats, params, z, k):
            k_a, k_e = jax.random.split(k)
            p2, s2, train_ret = self.adapt(params, obs_stats, z, k_a)
            return self.evaluate(p2, s2, z, k_e), s2, train_ret

        members = parallel.spread(jax.vmap(member, in_axes=(None, 0, 0, 0)), cfg.population, self.spreads, shared=1)
        fit, stats, train_ret = members(st.obs_stats, pop, tasks, keys)
        # a diverged member (NaN return) ranks last instead of poisoning the gradient
        ok = jnp.isfinite(fit)
        safe = jnp.where(ok, fit, jnp.min(jnp.where(ok, fit, jnp.inf)) - 1.0)
        es_state, _ = self.es.tell(k_tell, pop, -safe, es_state, self.es_params)  # evosax minimises
        obs_stats = jax.tree_util.tree_map(lambda x: jnp.mean(x, 0), stats)
        st = st.replace(es=es_state, obs_stats=obs_stats, key=key, step=st.step + 1)
        return st, {"fitness_mean": jnp.mean(safe), "fitness_max": jnp.max(safe), "fitness_min": jnp.min(safe),
                    "inner_train_return": jnp.nanmean(train_ret), "diverged_members": jnp.sum(~ok)}

    def policy(self, st: ESMAMLState):
        return self.theta(st), st.obs_stats

    def env_steps_per_update(self) -> int:
        c = self.cfg
        return c.population * (c.inner_updates * self.ppo.cfg.batch_size + c.eval_episodes * self.horizon)


def grad_estimate(es, es_params, es_state, fitness_fn, key):
    """``1/(N sigma) sum_i f(theta + sigma g_i) g_i`` for one antithetic population, with raw
    (unshaped) fitness ``fitness_fn(params)`` — the estimator OpenES applies (tests check it)."""
    pop, _ = es.ask(key, es_state, es_params)
    flat_pop = jax.vmap(lambda p: jax.flatten_util.ravel_pytree(p)[0])(pop)
    mean = jax.flatten_util.ravel_pytree(es.get_mean(es_state))[0]
    g = (flat_pop - mean) / es_state.std
    return jax.vmap(fitness_fn)(pop) @ g / (es.population_size * es_state.std)


def _build(env, cfg):
    from sim2real.common import config as config_lib

    opts = config_lib.from_dict(ESMAMLConfig, cfg.algo_options, "algo_options.")
    algo = ESMAML(env, cfg.ppo, cfg.dr, opts)
    algo.warm_start_from = opts.warm_start
    return algo


register("es_maml", _build)
