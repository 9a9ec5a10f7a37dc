"""Simulate recordings in MJX under a physics vector: full replays and short-horizon predictions.

Short-horizon (multiple-shooting) prediction starts every segment from the *measured* state, so
it stays meaningful for unstable or chaotic systems where an open-loop replay drifts away.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from sim2real.physics import stepper
from sim2real.physics.effects import EffectState
from sim2real.physics.params import clip
from sim2real.sysid.system import System


class Simulator:
    """Rollouts of one system at one sample period.

    Args:
      system: the identification subject.
      dt: sample period of the recordings; physics runs ``substeps`` steps per sample.
    """

    def __init__(self, system: System, dt: float):
        self.sys, self.dt = system, float(dt)
        self.substeps = max(1, int(round(dt / float(system.mj.opt.timestep))))
        self.h = self.dt / self.substeps
        m = system.mj
        self._off = [(i, m.jnt_qposadr[p.index]) for i, p in system.spec.of_kind("sensor_offset")]
        self.rollout = jax.jit(self._rollout)
        self.segments = jax.jit(jax.vmap(self._rollout, in_axes=(None, 0, 0, 0, 0, 0)))
        self.effect_states = jax.jit(self._effect_states)

    def _measure(self, z, qpos):
        for i, adr in self._off:
            qpos = qpos.at[adr].add(z[i])
        return qpos

    def _true(self, z, qpos):
        for i, adr in self._off:
            qpos = qpos.at[adr].add(-z[i])
        return qpos

    def _rollout(self, z, q0, v0, ctrl, qfrc, es):
        """Simulate ``H`` samples from measured ``q0 [nq]``, ``v0 [nv]``.

        Args:
          ctrl: ``[H, nu]`` commands; qfrc: ``[H, nv]`` known external forces.
          es: effect state (delay buffer, lag, backlash gap) at the segment's start.
        Returns:
          dict of ``qpos [H, nq]`` (as measured: with sensor offsets), ``qvel [H, nv]``,
          ``force [H, nu]`` (actuator force), ``ok [H]`` (finite).
        """
        z = clip(self.sys.spec, z)
        model = self.sys.physics.apply(z)
        model = model.replace(opt=model.opt.replace(timestep=self.h))
        data = self.sys.data0.replace(qpos=self._true(z, q0), qvel=v0)

        def step(carry, x):
            d, es = carry
            u, f = x
            d2, es2 = stepper.advance(self.sys.effects, model, z, d, es, u, self.dt, self.substeps, f)
            ok = jnp.isfinite(d2.qpos).all() & jnp.isfinite(d2.qvel).all() & (jnp.abs(d2.qvel) < 1e6).all()
            d2 = jax.tree_util.tree_map(lambda a, b: jnp.where(ok, a, b), d2, d)
            out = {"qpos": self._measure(z, d2.qpos), "qvel": d2.qvel, "force": d2.actuator_force, "ok": ok}
            return (d2, es2), out

        return jax.lax.scan(step, (data, es), (ctrl, qfrc))[1]

    def _effect_states(self, z, qpos, ctrl):
        """Effect state after each recorded command ``[T, ...]``: the command path (delay line,
        motor-lag filter, backlash gap) depends on the commands and positions only, so it is run
        over the whole recording and every prediction segment starts from its true state."""
        z = clip(self.sys.spec, z)
        fx = self.sys.effects

        def step(es, x):
            u, q = x
            _, es = fx.actuate(z, es, u, self._true(z, q), self.dt)
            return es, es

        return jax.lax.scan(step, fx.init_state(), (ctrl, qpos))[1]

    def initial_state(self) -> EffectState:
        return self.sys.effects.init_state()

    # ------------------------------------------------------------------------------------------
    def predict(self, z, qpos, qvel, ctrl, qfrc, horizon: int, stride: int | None = None, chunk: int = 32,
                first: int = 0):
        """Short-horizon predictions from measured states.

        ``first``: the first segment starts there. The effect states (delay line, lag filter,
        backlash gap) still come from the whole recording: a prediction on a recording's tail
        must not start a motor lag from rest (what slicing the recording would do).

        Segments are simulated ``chunk`` at a time (the last chunk padded), so one compiled
        function serves every recording of a given horizon.

        Returns ``(starts [S], dict of [S, H, .] arrays)``: segment ``s`` starts from the state
        at sample ``starts[s]`` and predicts samples ``starts[s] + 1 .. + H``.
        """
        T = len(qpos)
        horizon = int(min(horizon, T - 1))
        stride = stride or horizon
        starts = np.arange(min(int(first), max(T - horizon - 1, 0)), T - horizon, stride)
        zj = jnp.asarray(z, jnp.float32)
        es_all = self.effect_states(zj, jnp.asarray(qpos, jnp.float32), jnp.asarray(ctrl, jnp.float32))
        es0 = self.initial_state()
        outs = []
        for c0 in range(0, len(starts), chunk):
            st = starts[c0: c0 + chunk]
            pad = np.concatenate([st, np.full(chunk - len(st), st[0])])
            es = jax.tree_util.tree_map(
                lambda a, a0: jnp.where((pad > 0).reshape((-1,) + (1,) * a0.ndim), a[np.maximum(pad - 1, 0)], a0[None]),
                es_all, es0)
            u = np.stack([ctrl[s: s + horizon] for s in pad])
            f = np.stack([qfrc[s: s + horizon] for s in pad])
            out = self.segments(zj, jnp.asarray(qpos[pad], jnp.float32), jnp.asarray(qvel[pad], jnp.float32),
                                jnp.asarray(u, jnp.float32), jnp.asarray(f, jnp.float32), es)
            outs.append(jax.tree_util.tree_map(lambda a: np.asarray(a)[: len(st)], out))
        return starts, jax.tree_util.tree_map(lambda *a: np.concatenate(a), *outs)
