"""Inverse-dynamics (equation-error) residuals: what force the data needs that the model does not give.

For measured positions ``q`` (smoothed and differentiated: ``dq``, ``ddq``) and commands ``u``,

    r(z) = qfrc_actuator(effects(u), q, dq; z) + qfrc_known - qfrc_inverse(q, dq, ddq; z) - f_friction(dq; z)

is zero for a perfect model. It needs no simulation, so it works where open-loop replay diverges,
and it is (nearly) linear in most parameters: masses, damping, stiffness, payloads, friction
levels, gains. ``qfrc_inverse`` is MuJoCo's own ``mj_inverse`` on the model ``apply(z)`` builds;
the actuator path runs the effects library's ``actuate`` (delay, motor lag, backlash) over the
recorded commands, so the screen uses the same effect models as the simulator.
"""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from sim2real.physics.model_apply import to_mjmodel
from sim2real.sysid.derivatives import align_to_model, smooth_derivatives
from sim2real.sysid.system import System


@dataclasses.dataclass
class Segment:
    """One recording's smoothed signals (all ``[T, .]``) and the rows trusted for fitting."""

    name: str
    dt: float
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    ctrl: np.ndarray
    qfrc: np.ndarray
    keep: np.ndarray  # [T] bool: away from the filter's edges


class InverseDynamics:
    """Residuals ``r(z) [N, nv]`` over several recordings (rows concatenated)."""

    def __init__(self, system: System, recordings, window: int):
        self.sys = system
        self.segments = []
        for rec in recordings:
            qpos, ctrl, _, qfrc = system.arrays(rec)
            q, dq, ddq = align_to_model(*smooth_derivatives(qpos, rec.dt, window), rec.dt,
                                        float(system.mj.opt.timestep), system.rk4)
            keep = np.zeros(len(rec), bool)
            keep[window: len(rec) - window] = True
            self.segments.append(Segment(rec.name, rec.dt, q, dq, ddq, ctrl, qfrc, keep))
        m = system.mj
        self._dof = np.array([m.jnt_dofadr[m.actuator_trnid[a, 0]] for a in range(m.nu)])
        self._qadr = np.array([m.jnt_qposadr[m.actuator_trnid[a, 0]] for a in range(m.nu)])
        self._off_rows = [(i, m.jnt_qposadr[p.index]) for i, p in system.spec.of_kind("sensor_offset")]
        self._actuate = jax.jit(self._actuate_seq, static_argnums=2)
        # coefficient c(dq) [T, n_fric] of the Coulomb/Stribeck force c * dq, jitted once: run
        # eagerly it dispatches every small op of the friction model on every residual
        self._friction_coef = jax.jit(jax.vmap(lambda z, v: system.effects.friction_damping(z, v)[1],
                                               in_axes=(None, 0)))

    # ------------------------------------------------------------------------------------------
    def _actuate_seq(self, z, ctrl_and_q, dt):
        """Effects pipeline over a whole recording: ``[T, nu]`` commands -> applied commands."""
        ctrl, q = ctrl_and_q
        fx = self.sys.effects

        def step(es, x):
            u, qq = x
            u2, es = fx.actuate(z, es, u, qq, dt)
            return es, u2

        return jax.lax.scan(step, fx.init_state(), (ctrl, q))[1]

    def true_q(self, z, q):
        """Measured -> true positions: remove sensor offsets."""
        out = q.copy()
        for i, adr in self._off_rows:
            out[:, adr] = q[:, adr] - z[i]
        return out

    def actuator_qfrc(self, z, m: mujoco.MjModel, seg: Segment, q_true):
        """Generalised actuator force ``[T, nv]`` from the applied commands (joint transmissions)."""
        u = np.asarray(self._actuate(jnp.asarray(z, jnp.float32),
                                     (jnp.asarray(seg.ctrl, jnp.float32), jnp.asarray(q_true, jnp.float32)), seg.dt))
        out = np.zeros((len(u), m.nv))
        for a in range(m.nu):
            gear = m.actuator_gear[a, 0]
            length, vel = gear * q_true[:, self._qadr[a]], gear * seg.dq[:, self._dof[a]]
            b = m.actuator_biasprm[a]
            force = m.actuator_gainprm[a, 0] * u[:, a] + b[0] + b[1] * length + b[2] * vel
            if m.actuator_forcelimited[a]:
                force = np.clip(force, m.actuator_forcerange[a, 0], m.actuator_forcerange[a, 1])
            out[:, self._dof[a]] += gear * force
        return out

    def friction_qfrc(self, z, dq):
        """Force the Coulomb/Stribeck effect takes out of the motion ``[T, nv]`` (positive opposes)."""
        fx = self.sys.effects
        out = np.zeros_like(dq)
        if fx.fric_dof.size:
            c = self._friction_coef(jnp.asarray(z, jnp.float32), jnp.asarray(dq, jnp.float32))
            out[:, fx.fric_dof] = np.asarray(c) * dq[:, fx.fric_dof]
        return out

    @staticmethod
    def inverse(m: mujoco.MjModel, q, dq, ddq):
        d = mujoco.MjData(m)
        out = np.empty_like(dq)
        for t in range(len(q)):
            d.qpos[:], d.qvel[:], d.qacc[:] = q[t], dq[t], ddq[t]
            mujoco.mj_inverse(m, d)
            out[t] = d.qfrc_inverse
        return out

    def residual(self, z, parts=("act", "dyn")) -> np.ndarray:
        """``r(z) [N, nv]`` over the kept rows of every recording."""
        z = np.asarray(z, np.float32)
        m = to_mjmodel(self.sys.physics, z)
        rows = []
        for seg in self.segments:
            qt = self.true_q(z, seg.q)
            r = np.zeros_like(seg.dq)
            if "act" in parts:
                r += self.actuator_qfrc(z, m, seg, qt) + seg.qfrc
            if "dyn" in parts:
                r -= self.inverse(m, qt, seg.dq, seg.ddq) + self.friction_qfrc(z, seg.dq)
            rows.append(r[seg.keep])
        return np.concatenate(rows)

    def regressor(self, z, name: str, step: float, parts=("act", "dyn")) -> np.ndarray:
        """Finite-difference column ``d r / d z[name]`` (exact for parameters r is linear in)."""
        i = self.sys.spec.index(name)
        z1 = np.array(z, np.float32)
        z1[i] += step
        return (self.residual(z1, parts) - self.residual(z, parts)) / step

    def rows(self) -> np.ndarray:
        """Per kept row: index of the recording it comes from (for train/validation splits)."""
        return np.concatenate([np.full(seg.keep.sum(), k) for k, seg in enumerate(self.segments)])

    def stacked(self, field: str) -> np.ndarray:
        """A smoothed signal (``q``, ``dq``, ``ddq``, ``ctrl``) over the kept rows ``[N, .]``."""
        return np.concatenate([getattr(s, field)[s.keep] for s in self.segments])
