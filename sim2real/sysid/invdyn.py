"""Inverse-dynamics residuals for the report: what force the data needs that a model does not give.

For measured positions and their smoothed derivatives (``Trajectory``) and the recorded commands,

    r(z) = qfrc_actuator(u, q, dq; z) + qfrc_known + f_const(z) - qfrc_inverse(q, dq, ddq; z) - f_damping(dq; z)

per sample and DOF, with MuJoCo's own ``mj_forward`` / ``mj_inverse`` on the native model of
``z``. It differentiates noisy positions twice, so the diagnosis does not decide anything on it
(the simulation error does, ``fit.py``); it shows *where* the nominal model's forces are wrong
(``locate.regimes``: near velocity reversals, at high speed, ...), and the friction part of a fit.
Command-path effects (delay, lag, backlash) are not in it: the recorded command is applied as is.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from sim2real._precision import real
from sim2real.physics.model_apply import to_mjmodel


def rows(trajs, limit: int = 4000) -> list[np.ndarray]:
    """Sample indices per trajectory (evenly spaced, at most ``limit`` in all, away from the ends)."""
    total = sum(len(t) for t in trajs)
    step = max(1, total // limit)
    return [np.arange(t.window, len(t) - t.window, step) for t in trajs]


def residual(system, z, trajs, idx) -> dict[str, np.ndarray]:
    """``{'r': [N, nv], 'v': [N, nv], 'a': [N, nv], 'act': [N, nv], 'ctrl': [N, nu]}`` on rows ``idx``."""
    m = to_mjmodel(system.physics, z)
    d = mujoco.MjData(m)
    fx = system.effects
    out = {k: [] for k in ("r", "v", "a", "act", "ctrl")}
    const = np.zeros(m.nv)  # torque offsets: the same at every sample
    cdofs, cf = fx.constant_force(jnp.asarray(z, real()))
    np.add.at(const, cdofs, np.asarray(cf))  # (a dof may repeat)
    for tr, ix in zip(trajs, idx):
        # (the sensing hooks take one state [nq]: every sample its own)
        q = np.asarray(jax.vmap(lambda qm: fx.unsense(jnp.asarray(z, real()), qm))(jnp.asarray(tr.q[ix], real())))
        v, a, u, f = tr.v[ix], tr.a[ix], tr.ctrl[ix], tr.qfrc[ix]
        inv = np.empty_like(v)
        act = np.empty_like(v)
        for i in range(len(ix)):
            d.qpos[:], d.qvel[:], d.ctrl[:] = q[i], v[i], u[i]
            if m.na:
                d.act[:] = 0.0
            mujoco.mj_forward(m, d)
            act[i] = d.qfrc_actuator
            d.qacc[:] = a[i]
            mujoco.mj_inverse(m, d)
            inv[i] = d.qfrc_inverse
        fric = np.zeros_like(v)
        dofs = fx.damping_dofs
        if dofs.size and len(v):
            coef = _damping_coef(fx)(jnp.asarray(z, real()), jnp.asarray(v, real()))
            np.add.at(fric, (slice(None), dofs), np.asarray(coef) * v[:, dofs])  # a dof may repeat
        out["r"].append(act + f + const - inv - fric)
        out["v"].append(v)
        out["a"].append(a)
        out["act"].append(act)
        out["ctrl"].append(u)
    return {k: np.concatenate(v) for k, v in out.items()}


def _damping_coef(fx):
    """``jit(vmap)`` of the velocity-dependent damping coefficients (Coulomb friction, drag), once
    per effects object (run eagerly it dispatches every small op for every row)."""
    f = fx.__dict__.get("_coef_jit")
    if f is None:
        f = fx.__dict__["_coef_jit"] = jax.jit(jax.vmap(lambda z, v: fx.velocity_damping(z, v)[1], in_axes=(None, 0)))
    return f
