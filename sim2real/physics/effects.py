"""Unmodeled effects: physics a nominal model leaves out, as per-env parameters in ``z``.

Each effect is off at its default value and then *exactly* neutral (every branch is a
``jnp.where(enabled, effected, raw)``, so an off effect returns the raw array bit for bit).

Pipeline of one control step (``Env.step``)::

    action enters the delay line (once per control step); then every physics sub-step:
      delayed command (exact for fractional delays) -> motor_lag -> backlash
      -> [MuJoCo: saturation via forcerange]; velocity-dependent forces (Coulomb/Stribeck
      friction, quadratic drag: the ``damping`` hooks of ``physics/kinds/``) as damping terms
    measured qpos = qpos + sensor_offset + sensor_noise * N(0, 1)

The command path runs at the physics sub-step, so a delay or lag that is not a whole number of
control steps acts when it should (a 1.4-step delay switches the command 0.4 of a step late, not
blended over the step); with one sub-step per control step this is the per-step pipeline.

Velocity-dependent forces are written as damping ``c(v) >= 0`` added to ``dof_damping`` for the
sub-step (``kinds/coulomb.py`` says why); envs therefore keep ``eulerdamp`` enabled.
"""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from flax import struct

from sim2real.physics import kinds
from sim2real.physics.kinds.base import rows as _rows
from sim2real.physics.kinds.base import take
from sim2real.physics.kinds.gain import is_servo
from sim2real.physics.params import ParamSpec


@struct.dataclass
class EffectState:
    """Per-env effect memory.

    Attributes:
      action_buf: ``[D + 2, nu]`` past commands, newest first (for the action delay).
      lag: ``[nu]`` output of the first-order motor lag.
      gap: ``[nu]`` motor-side offset inside the backlash dead band.
      gap_vel: ``[nu]`` its rate.
    """

    action_buf: jax.Array
    lag: jax.Array
    gap: jax.Array
    gap_vel: jax.Array


@dataclasses.dataclass(frozen=True)
class EffectsConfig:
    """Static effect settings.

    Attributes:
      max_delay: longest action delay in control steps (size of the delay buffer).
      coulomb_eps: velocity scale of the tanh friction model (joint units / s).
      backlash_inertia: reflected motor inertia crossing the dead band; 0 = use dof armature
        (or 1e-2 where that is zero).
    """

    max_delay: int = 4
    coulomb_eps: float = 1e-3
    backlash_inertia: float = 0.0


class Effects:
    """Effect application for one model and spec (static; methods are pure)."""

    def __init__(self, m: mujoco.MjModel, spec: ParamSpec, cfg: EffectsConfig):
        self.cfg, self.spec = cfg, spec
        self.nu = m.nu
        act_joint = np.array([m.actuator_trnid[a, 0] for a in range(m.nu)], np.int32)
        self.act_qpos = np.array([m.jnt_qposadr[j] for j in act_joint], np.int32)
        self.act_dof = np.array([m.jnt_dofadr[j] for j in act_joint], np.int32)
        self.act_servo = np.array([is_servo(m, a) for a in range(m.nu)], bool)
        self.act_gain = np.array([m.actuator_gear[a, 0] * m.actuator_gainprm[a, 0] for a in range(m.nu)])
        arm = np.array([m.dof_armature[d] for d in self.act_dof])
        self.act_inertia = (np.full(m.nu, cfg.backlash_inertia) if cfg.backlash_inertia > 0
                            else np.where(arm > 0, arm, 1e-2))
        acts = np.arange(m.nu)
        self.r_backlash = _rows(spec, "backlash", acts)
        # the motor side's inertia may be a parameter too (the diagnosis fits it); else the static guess
        self.r_binertia = _rows(spec, "backlash_inertia", acts)
        self.r_lag = _rows(spec, "motor_lag", acts)
        self.r_gain = _rows(spec, "actuator_gain", acts)
        # velocity-dependent forces as damping: (plug-in, its dofs, its static data) per kind
        self._damping = [(k, *ds) for k in kinds.all_kinds() if (ds := k.damping_setup(m, spec, cfg)) is not None]
        self.damping_dofs = (np.concatenate([d for _, d, _ in self._damping]).astype(np.int32) if self._damping
                             else np.zeros((0,), np.int32))
        sj = [p.index for _, p in spec.of_kind("sensor_offset")]
        self.sense_qpos = np.array([m.jnt_qposadr[j] for j in sj], np.int32)
        self.r_off = _rows(spec, "sensor_offset", sj)
        self.r_noise = _rows(spec, "sensor_noise", sj)
        self.r_delay = spec.index("action_delay") if "action_delay" in spec else -1

    # ------------------------------------------------------------------------------
    def init_state(self) -> EffectState:
        nu = self.nu
        return EffectState(
            action_buf=jnp.zeros((self.cfg.max_delay + 2, nu)),
            lag=jnp.zeros(nu),
            gap=jnp.zeros(nu),
            gap_vel=jnp.zeros(nu),
        )

    def steady_state(self, ctrl) -> EffectState:
        """The command path at rest under ``ctrl [nu]``: the delay line full of it, the motor lag
        settled on it (how a recording of a drive that was already running starts)."""
        nu = self.nu
        return EffectState(
            action_buf=jnp.broadcast_to(ctrl, (self.cfg.max_delay + 2, nu)),
            lag=jnp.asarray(ctrl, jnp.float32) + jnp.zeros(nu),
            gap=jnp.zeros(nu),
            gap_vel=jnp.zeros(nu),
        )

    def push(self, es: EffectState, ctrl) -> EffectState:
        """A new command ``[nu]`` enters the delay line (once per control step)."""
        return es.replace(action_buf=jnp.concatenate([ctrl[None], es.action_buf[:-1]], axis=0))

    def delayed(self, z, es: EffectState, j, n: int):
        """The command applied during physics sub-step ``j`` of ``n`` of the current control step.

        A delay of ``d`` control steps (fractional allowed) shifts the piecewise-constant command
        by ``d``; sub-step ``j`` spans ``[j/n, (j+1)/n)`` of the step, so it sees the shifted
        command averaged over that span -- at most two neighbouring commands, weighted by how
        much of the span each covers. Exact for any ``d`` and ``n``; with ``n = 1`` it is the
        blend ``(1 - f) u[k] + f u[k+1]`` of the fractional part ``f``.
        """
        buf = es.action_buf
        ctrl = buf[0]
        if self.r_delay < 0:
            return ctrl
        d = z[self.r_delay]
        a = j / n - d                        # start of the span, in steps, relative to this step
        ka = jnp.floor(a)
        w = jnp.clip((ka + 1.0 - a) * n, 0.0, 1.0)   # share of the span inside step ka
        i = jnp.clip(-ka, 0, buf.shape[0] - 1).astype(jnp.int32)
        newer = jnp.maximum(i - 1, 0)
        delayed = w * buf[i] + (1.0 - w) * buf[newer]
        return jnp.where(d > 0, delayed, ctrl)

    def actuate(self, z, es: EffectState, j, n: int, qpos, h: float):
        """Command pipeline for physics sub-step ``j`` of ``n``: delay -> motor lag -> backlash.

        Args:
          z: ``[P]`` physics vector (clipped).
          es: effect state (the command of this control step already ``push``-ed).
          j: sub-step index (traced or static), ``n``: sub-steps per control step.
          qpos: ``[nq]`` current joint positions (true, for servo backlash).
          h: physics sub-step in seconds.
        Returns:
          ``(ctrl_applied [nu], new effect state)``.
        """
        u = self.delayed(z, es, j, n)
        # first-order motor lag, exact discretisation over the sub-step
        tau = take(z, self.r_lag)
        alpha = 1.0 - jnp.exp(-h / jnp.maximum(tau, 1e-9))
        lagged = es.lag + alpha * (u - es.lag)
        u = jnp.where(tau > 0, lagged, u)
        lag_state = u
        # backlash: dead band between actuator and joint
        b = take(z, self.r_backlash)
        gap, gap_vel = es.gap, es.gap_vel
        if self.nu:
            half = 0.5 * b
            q = qpos[self.act_qpos]
            # servo: the spring between target and joint acts only outside the band
            err = u - q
            servo_u = q + jnp.sign(err) * jnp.maximum(jnp.abs(err) - half, 0.0)
            # motor: torque reaches the joint only once the motor side has crossed the band
            gain = jnp.where(self.r_gain >= 0, take(z, self.r_gain), self.act_gain)
            torque = gain * u
            inertia = jnp.where(self.r_binertia >= 0, take(z, self.r_binertia, 1.0), self.act_inertia)
            gv = gap_vel + h * torque / jnp.maximum(inertia, 1e-9)
            g = gap + h * gv
            hit_hi, hit_lo = g >= half, g <= -half
            engaged = (hit_hi & (torque > 0)) | (hit_lo & (torque < 0))
            motor_u = jnp.where(engaged, u, 0.0)
            on = b > 0
            gap = jnp.where(on & ~self.act_servo, jnp.clip(g, -half, half), gap)
            gap_vel = jnp.where(on & ~self.act_servo, jnp.where(hit_hi | hit_lo, 0.0, gv), gap_vel)
            u = jnp.where(on, jnp.where(self.act_servo, servo_u, motor_u), u)
        return u, es.replace(lag=lag_state, gap=gap, gap_vel=gap_vel)

    def velocity_damping(self, z, qvel) -> tuple[np.ndarray, jax.Array]:
        """Velocity-dependent forces (Coulomb/Stribeck friction, drag, ...) as damping for one sub-step.

        Returns ``(dof indices [J], damping to add [J])`` (a dof may repeat: add, do not set);
        zero where every such effect is off.
        """
        if not self._damping:
            return self.damping_dofs, jnp.zeros((0,))
        return self.damping_dofs, jnp.concatenate([k.damping(data, z, qvel[dofs]) for k, dofs, data in self._damping])

    def sense(self, z, qpos, key):
        """Measured joint positions ``[nq]``: offsets and white noise on effect joints."""
        if self.sense_qpos.size == 0:
            return qpos
        off = take(z, self.r_off)
        std = take(z, self.r_noise)
        noise = std * jax.random.normal(key, off.shape)
        meas = qpos[self.sense_qpos] + off + noise
        return qpos.at[self.sense_qpos].set(jnp.where((off != 0) | (std > 0), meas, qpos[self.sense_qpos]))

    def measure(self, z, qpos):
        """Measured joint positions ``[nq]`` without noise: the true ones plus sensor offsets."""
        if self.sense_qpos.size == 0:
            return qpos
        return qpos.at[self.sense_qpos].add(take(z, self.r_off))

    def unsense(self, z, qpos_meas):
        """Joint positions ``[nq]`` implied by measured ones under ``z``'s sensor offsets (noise ignored).

        Starting a simulation from a measured state needs this: a hypothesised offset changes
        where the joint really was.
        """
        if self.sense_qpos.size == 0:
            return qpos_meas
        off = take(z, self.r_off)
        return qpos_meas.at[self.sense_qpos].add(-off)
