"""One control step of MJX physics with the effects library: shared by envs and the diagnosis tool."""
from __future__ import annotations

import jax
import jax.numpy as jnp
from sim2real._mjx import mjx

from sim2real.physics.effects import Effects, EffectState


def advance(effects: Effects, model: mjx.Model, z, data: mjx.Data, es: EffectState, ctrl, dt: float,
            substeps: int, qfrc_applied=None):
    """Apply ``ctrl [nu]`` through the effects and run ``substeps`` physics steps.

    Args:
      effects: effect application for this model.
      model: ``physics.apply(z)``.
      z: ``[P]`` clipped physics vector.
      data: current MJX data.
      es: effect state.
      ctrl: command in ctrl units.
      dt: control period (s).
      substeps: physics steps per control step.
      qfrc_applied: optional ``[nv]`` known external generalised force held over the step.
    Returns:
      ``(data, effect_state)`` after the step.
    """
    es = effects.push(es, ctrl)
    if effects.force_dofs.size:  # constant forces (torque offsets) join the known external ones
        dofs, f = effects.constant_force(z)
        base = jnp.zeros_like(data.qfrc_applied) if qfrc_applied is None else jnp.asarray(qfrc_applied)
        qfrc_applied = base.at[dofs].add(f.astype(base.dtype))
    if qfrc_applied is not None:
        data = data.replace(qfrc_applied=qfrc_applied)
    h = dt / substeps

    def substep(carry, j):
        d, es = carry
        u, es = effects.actuate(z, es, j, substeps, d.qpos, h, d.qvel, d.act)
        d = d.replace(ctrl=u, act=effects.activation(es, d.act))
        dofs, extra = effects.velocity_damping(z, d.qvel)
        m = model.replace(dof_damping=model.dof_damping.at[dofs].add(extra)) if dofs.size else model
        return (mjx.step(m, d), es), None

    (data, es), _ = jax.lax.scan(substep, (data, es), jnp.arange(substeps))
    return data, es
