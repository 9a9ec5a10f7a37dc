"""Motor lag: a first-order filter on the actuator command (the command path's second stage);
written into MJCF as MuJoCo's exact first-order filter. One time constant per actuator, or one
shared by every actuator (``motor_lag_all``: identical drives)."""
from __future__ import annotations

import jax.numpy as jnp
import mujoco
import numpy as np

from sim2real._precision import real
from sim2real.physics.kinds.base import ACTUATOR, Kind, rows, take
from sim2real.physics.params import Param

SHARED = "motor_lag_all"


def shared_param() -> Param:
    """The one time constant of every actuator's lag (the diagnosis declares it on models with
    two or more actuators; an actuator's own ``motor_lag`` wins where it is set)."""
    return Param(SHARED, 0.0, 0.0, 1.0, "s", "time constant of a first-order lag on every actuator's command "
                 "(one for all: identical drives)", SHARED)


def _taus(sc) -> np.ndarray:
    """The screening grid of a lag's time constant (s): from under a sample to a quarter second."""
    return np.geomspace(max(0.4 * sc.dt, 0.002), 0.25, 7)


def _write(ctx, a: int, name: str, v: float) -> None:
    # (an actuator with dynamics of its own cannot take a second filter: <numeric> only)
    if v > 0 and ctx.system.mj.actuator_dyntype[a] == 0:
        act = ctx.spec.actuator(ctx.system.actuators[a])
        act.dyntype = mujoco.mjtDyn.mjDYN_FILTEREXACT
        act.dynprm[0] = v
        # the command path filters the command and applies it in the same physics step; MuJoCo's
        # filter by default drives the force with the activation from before the step, one physics
        # step later (a hopper plant written that way showed as a 1-step delay beside its lag)
        act.actearly = 1
        act.actlimited = 0
    elif v > 0:
        ctx.only_numeric(name, "the actuator already has activation dynamics; MuJoCo takes one filter")


class MotorLag(Kind):
    owns = ("motor_lag",)
    attach = ACTUATOR
    declares = {"motor_lag": (0.0, 0.0, 1.0, "s", "time constant of a first-order lag on the actuator command")}
    order = 63
    effect = "motor_lag"
    candidate_order = 60.5  # searched before the other actuator effects
    command_order = 20

    def command_setup(self, m, spec, cfg):
        r = rows(spec, "motor_lag", np.arange(m.nu))
        shared = spec.index(SHARED) if SHARED in spec else -1
        return {"rows": r, "shared": shared} if (r >= 0).any() or shared >= 0 else None

    def command_state(self, data, ctrl):
        """``[nu]`` the filter's output."""
        return jnp.asarray(ctrl, real()) + jnp.zeros(len(data["rows"]), real())

    def command(self, data, z, lag, u, j, n, qpos, h, qvel=None):
        # exact discretisation over the sub-step
        tau = take(z, data["rows"])
        if data["shared"] >= 0:  # the shared constant where an actuator has none of its own
            tau = jnp.where(tau > 0, tau, z[data["shared"]])
        alpha = 1.0 - jnp.exp(-h / jnp.maximum(tau, 1e-9))
        u = jnp.where(tau > 0, lag + alpha * (u - lag), u)
        return u, u

    def command_rows(self, data):
        return [int(r) for r in data["rows"] if r >= 0] + ([int(data["shared"])] if data["shared"] >= 0 else [])

    def export(self, ctx, p, v) -> None:
        _write(ctx, p.index, p.name, v)

    def candidates(self, system, sc, add, target) -> None:
        an = system.actuators[target]
        taus = _taus(sc)
        add("motor_lag", an, [f"motor_lag:{an}"], [(t,) for t in taus], [float(taus[2])],
            [(0.25 * float(taus[0]), 0.25)])


class SharedMotorLag(Kind):
    """One lag for every actuator: a robot whose drives are alike (the hopper's three motors).
    Without it, forward selection adds one actuator's lag at a time, each explaining a share of
    the misfit, and a delay of the whole command, explaining more at once, stands in for them
    (with masses re-fitted to make up the rest). Searched only when asked for
    (``effects=[..., motor_lag_all]``): by default it named a false shared lag beside the truth
    on the 3-link arm's cases of the benchmark's focus list (``tuning.md`` step 59)."""

    owns = (SHARED,)
    order = 63.5
    effect = SHARED
    default_candidate = False

    def export(self, ctx, p, v) -> None:
        if v > 0:
            for a, an in enumerate(ctx.system.actuators):
                if ctx.values.get(f"motor_lag:{an}", 0.0) <= 0:  # (an actuator's own lag wins)
                    _write(ctx, a, p.name, v)
            ctx.native(p.name, "the same first-order filter on every actuator")

    def candidates(self, system, sc, add, target) -> None:
        if system.mj.nu < 2 or SHARED not in system.spec:
            return
        taus = _taus(sc)
        add(SHARED, "", [SHARED], [(t,) for t in taus], [float(taus[2])], [(0.25 * float(taus[0]), 0.25)])
