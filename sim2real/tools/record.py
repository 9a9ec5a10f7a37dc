"""Roll a trained policy on a target system and keep what its sensors logged, as recordings.

Two kinds of target:

* **the run's env with a physics vector** (MJX; ``z`` includes effects): logged once per control
  step, positions as the env's sensors measure them (offsets and noise included);
* **an MJCF file stepped by native MuJoCo** (``mj_step``): a diagnosis' ``fitted.xml``, or the
  "real" plant of a sim-to-sim study, whose unmodelled physics is MuJoCo's own
  (``frictionloss``, an actuator ``delay``, a heavier body) and owes nothing to
  ``sim2real.physics``. Logged at every physics step, the command held between control steps.

The policy sees what the env would show it (``env.observe`` of the measured positions); the
return is the env's own reward, which every env computes from ``qpos``/``qvel`` alone, so it is
the same quantity on both kinds of target. Recordings are written in the diagnosis' format
(``sysid/recordings.py``): ``time, qpos:<joint>, qvel:<joint>, ctrl:<actuator>``, row ``k``'s
command applied from ``time[k]`` to ``time[k+1]``.
"""
from __future__ import annotations

import dataclasses
import os

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from sim2real.envs.base import Env
from sim2real.physics import catalog


@dataclasses.dataclass
class Rollouts:
    """Episodes of one policy on one target.

    Attributes:
      dt: sample period of the logs (s).
      qpos: ``[E, T, nq]`` measured joint positions (m or rad), env joint order.
      qvel: ``[E, T, nv]`` joint velocities (m/s or rad/s).
      ctrl: ``[E, T, nu]`` commands (actuator ctrl units); ``ctrl[:, k]`` acts from sample k to k+1.
      length: ``[E]`` valid samples of each episode (an episode that terminates stops early,
        unless recorded ``until_end``).
      ret: ``[E]`` episode returns (the env's reward summed over control steps, up to the
        termination).
      joints, actuators: names (column order).
    """

    dt: float
    qpos: np.ndarray
    qvel: np.ndarray
    ctrl: np.ndarray
    length: np.ndarray
    ret: np.ndarray
    joints: list[str]
    actuators: list[str]

    def every(self, k: int) -> "Rollouts":
        """Every k-th sample (e.g. a physics-rate log at the control rate)."""
        return dataclasses.replace(self, dt=self.dt * k, qpos=self.qpos[:, ::k], qvel=self.qvel[:, ::k],
                                   ctrl=self.ctrl[:, ::k], length=(self.length - 1) // k + 1)

    def write(self, folder: str, prefix: str = "episode") -> list[str]:
        """One CSV per episode in ``folder`` (which must exist); returns the paths."""
        from sim2real.sysid.recordings import save_csv

        paths = []
        for e in range(len(self.ret)):
            n = int(self.length[e])
            cols = {f"qpos:{j}": self.qpos[e, :n, i] for i, j in enumerate(self.joints)}
            cols.update({f"qvel:{j}": self.qvel[e, :n, i] for i, j in enumerate(self.joints)})
            cols.update({f"ctrl:{a}": self.ctrl[e, :n, i] for i, a in enumerate(self.actuators)})
            path = os.path.join(folder, f"{prefix}_{e:03d}.csv")
            save_csv(path, np.arange(n) * self.dt, cols)
            paths.append(path)
        return paths


def policy(env: Env, ppo, params, obs_stats, z_ctx, deterministic: bool = True):
    """``act(obs [E, O], carry [E, H], first [E], key) -> (ctrl [E, nu], carry)``, jitted.

    ``z_ctx [P]``: the physics a context-conditioned policy is told (on a real system the true
    one is unknown: the run's nominal belief).
    """
    from sim2real.rl.episodes import action
    from sim2real.rl import networks

    ctx = ppo.ctx(jnp.asarray(z_ctx))

    @jax.jit
    def act(obs, carry, first, key):
        def one(o, c, f, k):
            return action(env, ppo, params, obs_stats, o, ctx, c, f, k, deterministic)

        return jax.vmap(one)(obs, carry, first, jax.random.split(key, obs.shape[0]))

    act.carry_size = networks.carry_size(ppo.cfg.net)
    return act


def native(env: Env, xml_path: str, act, episodes: int, key, noise: float = 0.0, progress=None,
           until_end: bool = False) -> Rollouts:
    """Episodes of ``act`` on the MJCF ``xml_path`` stepped by native MuJoCo.

    The plant's joints and actuators are matched to the env's by name (it may have more bodies,
    other masses, friction, delays, ...); its timestep must divide the env's control step.
    ``noise``: std of white noise on the measured positions (m or rad), seen by the policy and
    logged. Initial states are the env's (``env.init_qpos_qvel``). ``until_end``: an episode the
    env terminates (a hopper that falls) is stepped and logged on to the episode's length; its
    return still stops at the termination. A numerically diverged plant stops its log either way.
    """
    if not os.path.exists(xml_path):
        raise FileNotFoundError(f"target '{xml_path}' not found")
    try:
        m = mujoco.MjModel.from_xml_path(xml_path)
    except Exception as e:  # mujoco's parser error
        raise ValueError(f"target {xml_path}: cannot compile the MJCF: {e}") from None
    em = env.mj_model
    joints = catalog.names(em, mujoco.mjtObj.mjOBJ_JOINT)
    acts = catalog.names(em, mujoco.mjtObj.mjOBJ_ACTUATOR)
    jid = [catalog.lookup(m, mujoco.mjtObj.mjOBJ_JOINT, j, f"joint (target {xml_path}, needed by env '{env.name}')")
           for j in joints]
    aid = [catalog.lookup(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a, f"actuator (target {xml_path})") for a in acts]
    for j, i in zip(joints, jid):
        if m.jnt_type[i] != em.jnt_type[joints.index(j)]:
            raise ValueError(f"target {xml_path}: joint '{j}' is of another type than the env's")
    qadr = np.array([m.jnt_qposadr[i] for i in jid])
    vadr = np.array([m.jnt_dofadr[i] for i in jid])
    sub = env.dt / m.opt.timestep
    if abs(sub - round(sub)) > 1e-6 * sub or round(sub) < 1:
        raise ValueError(f"target {xml_path}: its timestep {m.opt.timestep:g} s does not divide the env's "
                         f"control step {env.dt:g} s")
    sub = int(round(sub))
    T = env.config.episode_length
    k_init, k_goal, k_noise, k_act = jax.random.split(key, 4)
    q0, v0 = jax.vmap(env.init_qpos_qvel)(jax.random.split(k_init, episodes))
    goal = jax.vmap(env.init_goal)(jax.random.split(k_goal, episodes))
    q0, v0 = np.asarray(q0, np.float64), np.asarray(v0, np.float64)
    datas = []
    for e in range(episodes):
        d = mujoco.MjData(m)
        d.qpos[qadr], d.qvel[vadr] = q0[e], v0[e]
        mujoco.mj_forward(m, d)
        datas.append(d)
    rng = np.random.default_rng(np.asarray(jax.random.key_data(k_noise)).ravel()[-1])
    n_s = T * sub + 1
    qpos = np.zeros((episodes, n_s, len(joints)))
    qvel = np.zeros_like(qpos)
    ctrl = np.zeros((episodes, n_s, len(acts)))
    length = np.full(episodes, n_s)
    ret = np.zeros(episodes)
    alive = np.ones(episodes, bool)  # the return counts while the env would not have terminated
    logged = np.ones(episodes, bool)  # stepped and logged (past the termination with ``until_end``)
    observe = jax.jit(jax.vmap(env.observe))
    data0 = env._data0

    @jax.jit
    def task(q0_, v0_, q1, v1, u, g):
        def one(a, b, c, d, uu, gg):
            r, term, _ = env.task(data0.replace(qpos=a, qvel=b), data0.replace(qpos=c, qvel=d), uu, gg)
            return r, term

        return jax.vmap(one)(q0_, v0_, q1, v1, u, g)

    def state():  # true joint positions and velocities [E, nq], env order
        return np.stack([d.qpos[qadr] for d in datas]), np.stack([d.qvel[vadr] for d in datas])

    def measure(k):
        q, v = state()
        if noise > 0:
            q = q + noise * rng.standard_normal(q.shape)
        qpos[:, k], qvel[:, k] = q, v
        return q, v

    carry = jnp.zeros((episodes, act.carry_size))
    first = jnp.ones(episodes, bool)
    q_meas, v_meas = measure(0)
    for t in range(T):
        obs = observe(jnp.asarray(q_meas, jnp.float32), jnp.asarray(v_meas, jnp.float32), goal)
        u, carry = act(obs, carry, first, jax.random.fold_in(k_act, t))
        u = np.asarray(u, np.float64)
        first = jnp.zeros(episodes, bool)
        q_before, v_before = state()
        live = np.nonzero(logged)[0]
        for e in live:
            datas[e].ctrl[aid] = u[e]
        for s in range(sub):  # the command is held over the control step; every physics step logged
            for e in live:
                mujoco.mj_step(m, datas[e])
            q_meas, v_meas = measure(t * sub + s + 1)
            ctrl[:, t * sub + s] = u
        ok = np.array([np.isfinite(d.qpos).all() and np.isfinite(d.qvel).all() for d in datas])
        q_after, v_after = state()
        r, term = task(*(jnp.asarray(x, jnp.float32) for x in (q_before, v_before, q_after, v_after, u)), goal)
        r, term = np.asarray(r), np.asarray(term) | ~ok
        ret += np.where(alive, np.where(ok, r, 0.0), 0.0)
        stop = logged & (~ok if until_end else term)
        length[stop] = (t + 1) * sub + 1
        alive &= ~term
        logged &= ~stop
        if progress is not None:
            progress(t + 1, T)
        if not logged.any():
            break
    ctrl[:, -1] = ctrl[:, -2]
    return Rollouts(float(m.opt.timestep), qpos, qvel, ctrl, length, ret, joints, acts)


def simulated(env: Env, z, act, episodes: int, key, until_end: bool = False) -> Rollouts:
    """Episodes of ``act`` on the env itself with physics ``z [P]`` (MJX), logged per control step;
    positions as the env's sensors give them (``sensor_offset``/``sensor_noise`` effects).
    ``until_end``: as in :func:`native`."""
    z = jnp.asarray(env.spec.validate(z, where=f"target physics for env '{env.name}'"))
    T = env.config.episode_length
    k_reset, k_run = jax.random.split(key)
    s0 = jax.jit(jax.vmap(env.reset, in_axes=(0, None)))(jax.random.split(k_reset, episodes), z)
    sense = jax.vmap(lambda q, k: env.effects.sense(z, q, k))

    @jax.jit
    def run(s0, key):
        def step(c, k):
            s, carry, alive, first, ret, n = c
            k_act, k_sense = jax.random.split(k)
            u, carry = act(s.obs, carry, first, k_act)
            s2 = jax.vmap(env.step, in_axes=(0, 0, None))(s, u, z)
            ret = ret + jnp.where(alive, s2.reward, 0.0)
            logged = jnp.ones_like(alive) if until_end else alive
            n = n + logged
            s = jax.tree_util.tree_map(lambda a, b: jnp.where(logged.reshape((-1,) + (1,) * (a.ndim - 1)), a, b), s2, s)
            alive = alive & ~s2.terminated
            q = sense(s.data.qpos, jax.random.split(k_sense, episodes))
            return (s, carry, alive, jnp.zeros_like(first), ret, n), (q, s.data.qvel, u)

        q0 = sense(s0.data.qpos, jax.random.split(jax.random.fold_in(key, 1), episodes))
        init = (s0, jnp.zeros((episodes, act.carry_size)), jnp.ones(episodes, bool), jnp.ones(episodes, bool),
                jnp.zeros(episodes), jnp.zeros(episodes, jnp.int32))
        (_, _, _, _, ret, n), (q, v, u) = jax.lax.scan(step, init, jax.random.split(key, T))
        return q0, s0.data.qvel, q, v, u, ret, n

    q0, v0, q, v, u, ret, n = (np.asarray(x, np.float64) for x in run(s0, k_run))
    qpos = np.concatenate([q0[:, None], np.swapaxes(q, 0, 1)], 1)
    qvel = np.concatenate([v0[:, None], np.swapaxes(v, 0, 1)], 1)
    u = np.swapaxes(u, 0, 1)
    ctrl = np.concatenate([u, u[:, -1:]], 1)
    em = env.mj_model
    return Rollouts(env.dt, qpos, qvel, ctrl, n.astype(int) + 1, ret,
                    catalog.names(em, mujoco.mjtObj.mjOBJ_JOINT), catalog.names(em, mujoco.mjtObj.mjOBJ_ACTUATOR))


def save(rolls: Rollouts, what: dict, folder: str, inputs=(), overwrite: bool = False) -> list[str]:
    """Write the recordings and ``record.json`` into ``folder``, staged (``sim2real.common.output``: the
    folder appears complete or not at all; only a recordings folder sim2real made is replaced).
    Returns the recordings' final paths."""
    import json

    from sim2real.common import output

    with output.staged(folder, "recordings", inputs=inputs, overwrite=overwrite) as tmp:
        names = [os.path.basename(p) for p in rolls.write(tmp)]
        with open(os.path.join(tmp, "record.json"), "w") as f:
            json.dump(what, f, indent=2)
    return [os.path.join(folder, n) for n in names]


def parse_target(text: str) -> tuple[str, dict[str, float]]:
    """``''`` (the run's physics), ``PATH.xml`` (native MuJoCo) or ``name=v,name=v`` (the env with
    those physics on the run's) -> ``(xml or '', {name: value})``."""
    text = text.strip()
    if not text:
        return "", {}
    if "=" not in text:
        return text, {}
    values = {}
    for item in text.split(","):
        name, _, v = item.partition("=")
        try:
            values[name.strip()] = float(v)
        except ValueError:
            raise ValueError(f"target: cannot read '{item}' as name=value") from None
    return "", values


@dataclasses.dataclass
class RecordConfig:
    """What ``scripts/record.py`` rolls and where it writes (``key=value`` on its command line).

    Attributes:
      run: the trained run folder (its ``config.yaml``).
      target: an MJCF file (native MuJoCo), ``name=value,...`` (the run's env with those physics
        values), or empty (the run's own physics).
      episodes: episodes to record (>= 1).
      out: the recordings folder (``episode_000.csv``..., ``record.json``).
      seed: initial states and noise; run_seed: which of the run's seeds acts.
      noise: std of the position sensor's noise on an MJCF target (m or rad, >= 0).
      deterministic: the policy's mean action (``false``: sampled, more excitation).
      until_end: step and log an episode the env terminates (a fall) on to its full length, as a
        lab's logger keeps running after a robot falls (the return still stops at the fall).
      overwrite: replace an earlier recordings folder (only one sim2real made).
      progress: a progress bar.
    """
    run: str = ""
    target: str = ""
    episodes: int = 3
    out: str = ""
    seed: int = 0
    run_seed: int = 0
    noise: float = 0.0
    deterministic: bool = True
    until_end: bool = False
    overwrite: bool = False
    progress: bool = True

    def __post_init__(self):
        from sim2real.common.config import ConfigError

        if not self.run or not self.out:
            raise ConfigError("record needs run=RUN_DIR and out=DIR (target=PATH.xml or name=value,...)")
        if self.episodes < 1:
            raise ConfigError(f"episodes={self.episodes}: must be a positive integer")
        if not self.noise >= 0:
            raise ConfigError(f"noise={self.noise}: must be >= 0 (a standard deviation)")


def from_run(run_dir: str, target: str, episodes: int, seed: int = 0, run_seed: int = 0, noise: float = 0.0,
             deterministic: bool = True, progress=None, until_end: bool = False) -> tuple[Rollouts, dict]:
    """Episodes of seed ``run_seed``'s policy of a run on ``target`` (see :func:`parse_target`;
    ``until_end``: see :func:`native`).

    Returns the rollouts and a description of what was rolled (for ``record.json``).
    """
    from sim2real.training.runs import load_policy

    cfg, env, algo, params, stats = load_policy(run_dir)
    if not 0 <= run_seed < cfg.num_seeds:
        raise ValueError(f"run_seed={run_seed}: run '{run_dir}' has seeds 0..{cfg.num_seeds - 1}")
    params, stats = jax.tree_util.tree_map(lambda x: x[run_seed], (params, stats))
    base = np.asarray(algo.space.base, np.float32)
    act = policy(env, algo.ppo, params, stats, base, deterministic)
    key = jax.random.PRNGKey(seed)
    xml, values = parse_target(target)
    if xml:
        r = native(env, xml, act, episodes, key, noise, progress, until_end)
        what = {"target": os.path.abspath(xml), "simulator": f"native MuJoCo {mujoco.__version__} (mj_step)"}
    else:
        if noise:
            raise ValueError("noise= applies to an MJCF target; on the env set its sensor_noise physics instead")
        z = base.copy()
        for n, v in values.items():
            z[env.spec.index(n)] = v
        r = simulated(env, z, act, episodes, key, until_end)
        what = {"target": {n: float(z[env.spec.index(n)]) for n in values} or "the run's physics",
                "simulator": "the run's env (MJX)"}
    what.update(run=os.path.abspath(run_dir), env=cfg.env, run_seed=run_seed, seed=seed, episodes=episodes,
                deterministic=deterministic, until_end=until_end, noise=noise, sample_period=r.dt,
                returns=[round(float(x), 4) for x in r.ret], mean_return=float(np.mean(r.ret)))
    return r, what
