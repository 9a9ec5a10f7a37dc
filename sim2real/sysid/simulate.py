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

    def _measure(self, z, qpos):
        for i, adr in self._off:
            qpos = qpos.at[adr].add(z[i])
        return qpos

    def _true(self, z, qpos):
        for i, adr in self._off:
            qpos = qpos.at[adr].add(-z[i])
        return qpos

    def _rollout(self, z, q0, v0, ctrl, qfrc, past_ctrl):
        """Simulate ``H`` samples from measured ``q0 [nq]``, ``v0 [nv]``.

        Args:
          ctrl: ``[H, nu]`` commands; qfrc: ``[H, nv]`` known external forces.
          past_ctrl: ``[D + 2, nu]`` commands before the segment, newest first (delay/lag memory).
        Returns:
          dict of ``qpos [H, nq]`` (as measured: with sensor offsets), ``qvel [H, nv]``,
          ``force [H, nu]`` (actuator force), ``ok [H]`` (finite).
        """
        z = clip(self.sys.spec, z)
        model = self.sys.physics.apply(z)
        model = model.replace(opt=model.opt.replace(timestep=self.h))
        data = self.sys.data0.replace(qpos=self._true(z, q0), qvel=v0)
        es0 = self.sys.effects.init_state()
        es = EffectState(action_buf=past_ctrl, lag=past_ctrl[0], gap=es0.gap, gap_vel=es0.gap_vel)

        def step(carry, x):
            d, es = carry
            u, f = x
            d2, es2 = stepper.advance(self.sys.effects, model, z, d, es, u, self.dt, self.substeps, f)
            ok = jnp.isfinite(d2.qpos).all() & jnp.isfinite(d2.qvel).all() & (jnp.abs(d2.qvel) < 1e6).all()
            d2 = jax.tree_util.tree_map(lambda a, b: jnp.where(ok, a, b), d2, d)
            out = {"qpos": self._measure(z, d2.qpos), "qvel": d2.qvel, "force": d2.actuator_force, "ok": ok}
            return (d2, es2), out

        return jax.lax.scan(step, (data, es), (ctrl, qfrc))[1]

    # ------------------------------------------------------------------------------------------
    def past(self, ctrl: np.ndarray, i: int) -> np.ndarray:
        """Commands before sample ``i``, newest first, ``[D + 2, nu]`` (zeros before the start)."""
        D = self.sys.effects.cfg.max_delay + 2
        idx = i - 1 - np.arange(D)
        out = np.where((idx >= 0)[:, None], ctrl[np.maximum(idx, 0)], 0.0)
        return out.astype(np.float32)

    def predict(self, z, qpos, qvel, ctrl, qfrc, horizon: int, stride: int | None = None):
        """Short-horizon predictions from measured states.

        Returns ``(starts [S], dict of [S, H, .] arrays)``: segment ``s`` starts from the state
        at sample ``starts[s]`` and predicts samples ``starts[s] + 1 .. + H``.
        """
        T = len(qpos)
        horizon = int(min(horizon, T - 1))
        stride = stride or horizon
        starts = np.arange(0, T - horizon, stride)
        q0, v0 = qpos[starts], qvel[starts]
        u = np.stack([ctrl[s: s + horizon] for s in starts])
        f = np.stack([qfrc[s: s + horizon] for s in starts])
        past = np.stack([self.past(ctrl, s) for s in starts])
        out = self.segments(jnp.asarray(z, jnp.float32), *(jnp.asarray(a, jnp.float32) for a in (q0, v0, u, f, past)))
        return starts, jax.tree_util.tree_map(np.asarray, out)

