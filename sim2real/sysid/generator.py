"""Concealed-effect recordings: a "true" plant = nominal model + one hidden effect + sensor noise.

The diagnosis sees only the nominal MJCF and the recordings; the benchmark
(``benchmarks/concealed_effects.py``) compares what it names with what was hidden.
"""
from __future__ import annotations

import dataclasses
import functools
import os

import jax
import numpy as np

import jax.numpy as jnp

from sim2real.envs.base import ASSETS
from sim2real.physics import stepper
from sim2real.physics.params import clip
from sim2real.sysid.recordings import save_csv
from sim2real.sysid.system import System

SYSTEMS = {  # name -> (MJCF in envs/assets, seconds recorded, excitation scale of the ctrl range)
    "pendulum": ("pendulum.xml", 30.0, 1.0),
    "cartpole": ("cartpole.xml", 30.0, 0.6),
    "arm2": ("arm2.xml", 30.0, 0.8),
    "prismatic": ("prismatic.xml", 20.0, 1.0),
}


@dataclasses.dataclass(frozen=True)
class Case:
    """One hidden truth: ``effect`` with ``values`` (spec name -> value) on ``system``.

    ``nominal`` perturbs nominal parameters too (``effect == 'none'``: parameter-only cases).
    """

    system: str
    effect: str
    target: str
    values: tuple[tuple[str, float], ...]
    nominal: tuple[tuple[str, float], ...] = ()
    noise: float = 1e-4
    seed: int = 0

    @property
    def label(self) -> str:
        return f"{self.system}/{self.effect}@{self.target}" if self.target else f"{self.system}/{self.effect}"


def excitation(system: System, T: int, dt: float, rng, scale: float) -> np.ndarray:
    """Commands ``[T, nu]``: a sum of random sines plus smoothed steps, inside the ctrl range.

    For position servos (the prismatic drive) it is a smooth back-and-forth reference with stops,
    like the EMPS trajectories.
    """
    m = system.mj
    t = np.arange(T) * dt
    u = np.zeros((T, m.nu))
    for a in range(m.nu):
        lo, hi = (m.actuator_ctrlrange[a] if m.actuator_ctrllimited[a] else (-1.0, 1.0))
        if m.actuator_biasprm[a, 1] != 0:  # servo: reference positions with holds
            knots = rng.uniform(0.0, 0.2, size=int(t[-1] / 2) + 2)
            x = np.interp(t, np.arange(len(knots)) * 2.0, knots)
            k = int(0.4 / dt)
            u[:, a] = np.convolve(np.pad(x, (k, k), mode="edge"), np.ones(2 * k + 1) / (2 * k + 1), "valid")
            continue
        sig = np.zeros(T)
        for _ in range(4):
            f = rng.uniform(0.05, 1.5)
            sig += rng.uniform(0.3, 1.0) * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
        steps = np.repeat(rng.uniform(-1, 1, size=T // int(1.0 / dt) + 1), int(1.0 / dt))[:T]
        sig = sig / np.abs(sig).max() * 0.7 + 0.3 * steps
        mid, half = (lo + hi) / 2, (hi - lo) / 2
        u[:, a] = np.clip(mid + scale * half * sig, lo, hi)
    return u


@functools.lru_cache(maxsize=None)
def _plant(name: str):
    """One system and jitted rollout per plant (it compiles once per process).

    ``rollout(z, q0 [nq], ctrl [T, nu]) -> (qpos [T, nq] as measured, ok [T])``: one control step
    per sample at the model's timestep, through the effects library (the model-matched truth).
    """
    system = System(os.path.join(ASSETS, SYSTEMS[name][0]))
    dt = float(system.mj.opt.timestep)

    def rollout(z, q0, ctrl):
        z = clip(system.spec, z)
        model = system.physics.apply(z)
        fx = system.effects
        data = system.data0.replace(qpos=fx.unsense(z, q0))

        def step(carry, u):
            d, es = carry
            d, es = stepper.advance(fx, model, z, d, es, u, dt, 1)
            ok = jnp.isfinite(d.qpos).all() & jnp.isfinite(d.qvel).all()
            return (d, es), (fx.measure(z, d.qpos), ok)

        return jax.lax.scan(step, (data, fx.init_state()), ctrl)[1]

    return system, jax.jit(rollout), dt


def record(case: Case, path: str) -> dict:
    """Simulate ``case`` and write its recording CSV; returns the true physics (spec name -> value)."""
    _, seconds, scale = SYSTEMS[case.system]
    system, rollout, dt = _plant(case.system)
    T = int(seconds / dt)
    rng = np.random.default_rng(case.seed)
    truth = dict(case.nominal) | dict(case.values)
    z = system.spec.vector(truth)
    ctrl = excitation(system, T, dt, rng, scale)
    q0 = np.asarray(system.mj.qpos0, np.float32) + rng.uniform(-0.05, 0.05, system.mj.nq).astype(np.float32)
    if case.system == "cartpole":  # start hanging down, slightly off
        q0[1] = np.pi + rng.uniform(-0.1, 0.1)
    qpos, ok = rollout(jnp.asarray(z), jnp.asarray(q0), jnp.asarray(ctrl, jnp.float32))
    if not bool(np.all(ok)):
        raise RuntimeError(f"{case.label}: the true plant diverged while recording")
    qpos = np.asarray(qpos, np.float64)
    qpos = qpos + case.noise * rng.standard_normal(qpos.shape)
    cols = {f"qpos:{j}": qpos[:, k] for k, j in enumerate(system.joints)}
    # the command recorded at sample k drove the step k -> k+1, which produced qpos[k]; align as
    # time[k] = state before the command: prepend the initial state, drop the last command
    # (the rollout takes its initial positions as *measured*: q0 is the first measurement)
    q_init = np.asarray(q0, np.float64)[None] + case.noise * rng.standard_normal((1, system.mj.nq))
    for k, j in enumerate(system.joints):
        cols[f"qpos:{j}"] = np.concatenate([q_init[:, k], qpos[:-1, k]])
    for a, name in enumerate(system.actuators):
        cols[f"ctrl:{name}"] = ctrl[:, a]
    save_csv(path, np.arange(T) * dt, cols)
    return truth
