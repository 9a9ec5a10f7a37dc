"""Unmodeled effects: physics a nominal model leaves out, as per-env parameters in ``z``.

Each effect is off at its default value and then *exactly* neutral (every branch is a
``jnp.where(enabled, effected, raw)``, so an off effect returns the raw array bit for bit).

Pipeline of one control step (``Env.step``); every stage is a kind plug-in (``physics/kinds/``,
its ``command`` / ``damping`` / ``sense`` hooks), run here in order::

    action enters the delay line (once per control step); then every physics sub-step:
      delayed command (exact for fractional delays) -> motor_lag -> backlash
      -> [MuJoCo: saturation via forcerange]; velocity-dependent forces (Coulomb/Stribeck
      friction, quadratic drag: the ``damping`` hooks of ``physics/kinds/``) as damping terms;
      constant generalised forces (torque offsets: the ``force`` hooks) in ``qfrc_applied``
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

from sim2real._precision import real
from sim2real.physics import kinds
from sim2real.physics.params import ParamSpec


# Per-env effect memory: ``{"ctrl": [nu] the command of this control step, <kind>: its memory}``
# for every stage of the command path on this model (``kinds/delay.py``: the delay line
# ``[D + 2, nu]``; ``lag.py``: the filter's output ``[nu]``; ``backlash.py``: the motor side's
# position in the band and its velocity). A dict, so a new stage brings its own entry.
EffectState = dict


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
    """Effect application for one model and spec (static; methods are pure): the command path,
    the velocity-dependent forces and sensing, each a list of the kind plug-ins that act on it."""

    def __init__(self, m: mujoco.MjModel, spec: ParamSpec, cfg: EffectsConfig):
        self.nu = m.nu
        self.cfg = cfg
        # the command path's stages, in their order: (plug-in, its name in the state, static data)
        stages = sorted((k for k in kinds.all_kinds() if k.command_order is not None), key=lambda k: k.command_order)
        self._command = [(k, k.owns[0], d) for k in stages if (d := k.command_setup(m, spec, cfg)) is not None]
        # rows of z that switch a stage on (its memory matters only then: sysid.shooting), all and per stage
        self.stage_rows = {name: np.array(k.command_rows(d), np.int32) for k, name, d in self._command}
        self.command_rows = np.array([r for rows in self.stage_rows.values() for r in rows], np.int32)
        # stages worth replaying without when they are off (``Kind.skip_when_off``)
        self.skippable = tuple(name for k, name, _ in self._command if k.skip_when_off and len(self.stage_rows[name]))
        # velocity-dependent forces as damping: (plug-in, its dofs, its static data) per kind
        self._damping = [(k, *ds) for k in kinds.all_kinds() if (ds := k.damping_setup(m, spec, cfg)) is not None]
        self.damping_dofs = (np.concatenate([d for _, d, _ in self._damping]).astype(np.int32) if self._damping
                             else np.zeros((0,), np.int32))
        # constant generalised forces: (plug-in, its dofs, its static data) per kind
        self._force = [(k, *fs) for k in kinds.all_kinds() if (fs := k.force_setup(m, spec)) is not None]
        self.force_dofs = (np.concatenate([d for _, d, _ in self._force]).astype(np.int32) if self._force
                           else np.zeros((0,), np.int32))
        # sensing (one kind today: a second one would need its own noise key)
        self._sense = [(k, d) for k in kinds.all_kinds() if (d := k.sense_setup(m, spec)) is not None]

    # ------------------------------------------------------------------------------
    def init_state(self) -> EffectState:
        """A fresh start: every memory at zero."""
        return self.steady_state(jnp.zeros(self.nu))

    def steady_state(self, ctrl) -> EffectState:
        """The command path at rest under ``ctrl [nu]``: the delay line full of it, the motor lag
        settled on it (how a recording of a drive that was already running starts)."""
        es = {"ctrl": jnp.asarray(ctrl, real()) + jnp.zeros(self.nu, real())}
        es.update({name: k.command_state(d, ctrl) for k, name, d in self._command})
        return es

    def push(self, es: EffectState, ctrl) -> EffectState:
        """A new command ``[nu]`` arrives (once per control step)."""
        out = {"ctrl": jnp.asarray(ctrl, real())}  # (a strong type, as the state it replaces)
        out.update({name: k.push(d, es[name], ctrl) for k, name, d in self._command})
        return out

    def actuate(self, z, es: EffectState, j, n: int, qpos, h: float, qvel=None, act=None, skip=()):
        """The command path for physics sub-step ``j`` of ``n``: each stage in turn (delay -> motor
        lag -> backlash).

        Args:
          z: ``[P]`` physics vector (clipped).
          es: effect state (the command of this control step already ``push``-ed).
          j: sub-step index (traced or static), ``n``: sub-steps per control step.
          qpos, qvel: ``[nq]``, ``[nv]`` current joint positions and velocities (true; the
            backlash stage moves its dead band with the joint).
          h: physics sub-step in seconds.
          act: ``[na]`` current activations (the backlash's integrating servo starts from them).
          skip: names of stages known to be off (every row of ``stage_rows`` at 0; static):
            ``Kind.command_off`` runs in their place (``sysid.shooting``'s replay of the command
            path, where a backlash's sums are nine tenths of the time on a 3-link arm).
        Returns:
          ``(ctrl_applied [nu], new effect state)``; the activations for the sub-step are
          ``activation(new effect state, act)``.
        """
        u, out = es["ctrl"], dict(es)
        for k, name, d in self._command:
            # (the activations only to a stage that sets them: a plug-in written before it keeps working)
            kw = {"act": act} if k.sets_act(d) else {}
            if name in skip:
                u, out[name] = k.command_off(d, es[name], u)
            else:
                u, out[name] = k.command(d, z, es[name], u, j, n, qpos, h, qvel, **kw)
        return u, out

    def activation(self, es: EffectState, act):
        """``act [na]`` as the command path sets it for the coming sub-step (``Kind.activation``:
        a backlash in front of an integrating servo holds the servo's setpoint itself; ``act``
        unchanged where no stage sets one)."""
        for k, name, d in self._command:
            act = k.activation(d, es[name], act)
        return act

    def rebase(self, es: EffectState, dv) -> EffectState:
        """The command path's state when the joint velocities it was run with change by ``dv
        [nv]`` (``Kind.rebase``; ``sysid.shooting``: a segment's initial velocity refined away from
        the estimate its command path was replayed with)."""
        out = dict(es)
        for k, name, d in self._command:
            out[name] = k.rebase(d, es[name], dv)
        return out

    def velocity_damping(self, z, qvel) -> tuple[np.ndarray, jax.Array]:
        """Velocity-dependent forces (Coulomb/Stribeck friction, drag, ...) as damping for one sub-step.

        Returns ``(dof indices [J], damping to add [J])`` (a dof may repeat: add, do not set);
        zero where every such effect is off.
        """
        if not self._damping:
            return self.damping_dofs, jnp.zeros((0,))
        return self.damping_dofs, jnp.concatenate([k.damping(data, z, qvel[dofs]) for k, dofs, data in self._damping])

    def constant_force(self, z) -> tuple[np.ndarray, jax.Array]:
        """State-independent generalised forces (torque offsets): ``(dof indices [J], force [J])``
        in N or N m (a dof may repeat: add, do not set); zero where every such effect is off."""
        if not self._force:
            return self.force_dofs, jnp.zeros((0,))
        return self.force_dofs, jnp.concatenate([k.force(data, z) for k, _, data in self._force])

    def sense(self, z, qpos, key):
        """Measured joint positions ``[nq]``: offsets and white noise on effect joints."""
        for k, d in self._sense:
            qpos = k.sense(d, z, qpos, key)
        return qpos

    def measure(self, z, qpos):
        """Measured joint positions ``[nq]`` without noise: the true ones plus sensor offsets."""
        for k, d in self._sense:
            qpos = k.measure(d, z, qpos)
        return qpos

    def unsense(self, z, qpos_meas):
        """Joint positions ``[nq]`` implied by measured ones under ``z``'s sensor offsets (noise ignored).

        Starting a simulation from a measured state needs this: a hypothesised offset changes
        where the joint really was.
        """
        for k, d in reversed(self._sense):
            qpos_meas = k.unsense(d, z, qpos_meas)
        return qpos_meas
