"""Recordings logged in other units or conventions than the model's: degrees for a hinge's
radians, millimetres for a slide's metres, a joint counted the other way, an angle's zero half a
turn from the model's (a pendulum's angle from upright where the model's zero hangs).

The model's joints are in rad and m; a logger that writes degrees (a servo's or a hobby encoder's
native unit) gives angles 57x too large, and nothing else in the data says so: a pendulum logged
in degrees was answered `none`, "the model misfits by 92.7x what the noise leaves", with no word on
why (``benchmarks/results/new_user_probes/twelfth_wave.txt``); one whose encoder counts the other
way was named a false payload, 7620x left unexplained, and so was one whose angle was counted from
upright, 426x. Where the kept model leaves motion unexplained, ``logged_units`` asks the nominal
model whether the recordings read in another unit or convention are predicted far better: short
native-MuJoCo predictions from the recorded states under the recorded commands, their error over
each signal's own spread (so a unit cancels where the physics is linear in it and a servo's
command scales with its joint: such data cannot tell the units apart, and no hint is given). ``force_units`` does the same for measured force columns (a
motor's current logged for its torque). Where either speaks, the diagnosis' answer, if it named
effects, is ``inconclusive``: what was fitted may stand in for the misread data.
"""
from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from sim2real.physics.kinds.base import actuator_joint
from sim2real.physics.kinds.gain import is_servo
from sim2real.physics.model_apply import to_mjmodel
from sim2real.sysid import native

# joint type: the readings tried, (scale, offset, words): the model's position is scale x the logged
# one + offset (a half turn: a pendulum's angle counted from upright where the model's zero hangs)
OTHER = {int(mujoco.mjtJoint.mjJNT_HINGE): ((np.pi / 180.0, 0.0, "as degrees"), (-1.0, 0.0, "with its sign flipped"),
                                            (1.0, np.pi, "with its zero half a turn away")),
         int(mujoco.mjtJoint.mjJNT_SLIDE): ((1e-3, 0.0, "as millimetres"), (-1.0, 0.0, "with its sign flipped"))}
GAIN = 4.0  # read in the other unit, the predictions' error at most this share of the logged one's
STARTS = 12  # predictions per recording
SHAPE = 0.02  # a force column's scaled prediction leaves at most this share of its mean square


def _scaled(tr, qa: list[int], da: list[int], s, c, acts: list[int], sa, ca):
    """``tr`` read otherwise: the positions ``qa`` as ``s * q + c``, their dofs ``da`` (velocities,
    accelerations, a measured qvel) multiplied by ``s``, the commands ``acts`` as ``sa * u + ca``
    (the smoothing is linear: the same as smoothing the data read so)."""
    q, v, a, u = tr.q.copy(), tr.v.copy(), tr.a.copy(), tr.ctrl.copy()
    q[:, qa] = q[:, qa] * s + c
    v[:, da] *= s
    a[:, da] *= s
    u[:, acts] = u[:, acts] * sa + ca
    qvel = None if tr.qvel is None else tr.qvel.copy()
    if qvel is not None:
        qvel[:, da] *= s
    sigma_q = tr.sigma_q.copy()
    sigma_q[qa] *= np.abs(s)
    return dataclasses.replace(tr, q=q, v=v, a=a, ctrl=u, qvel=qvel, sigma_q=sigma_q)


def _servos(m: mujoco.MjModel, joints: list[int]) -> list[int]:
    """The actuators on ``joints`` whose command is a position or a velocity (a bias that pulls the
    joint to it: ``position``, ``velocity``, an affine ``general``; ``intvelocity``)."""
    on = [a for a in range(m.nu) if actuator_joint(m, a) in joints]
    return [a for a in on if np.any(m.actuator_biasprm[a, 1:3] != 0)
            or m.actuator_dyntype[a] == mujoco.mjtDyn.mjDYN_INTEGRATOR]


def prediction_error(system, m: mujoco.MjModel, trajs, horizon: int) -> float:
    """The native model ``m``'s short predictions (``horizon`` samples, ``STARTS`` per recording,
    ``mj_step`` at the diagnosis' physics step: ``to_mjmodel`` of ``system``'s physics) from the
    recorded positions and velocity estimates under the recorded commands: RMS error over each
    position column's spread (its std over the recordings, at least its noise); activations at
    rest where each starts (``native.activation_at``); a diverged prediction counts as 1e3 (its
    squared error 1e6)."""
    d = mujoco.MjData(m)
    q_all = np.concatenate([tr.q for tr in trajs])
    spread = np.maximum(q_all.std(0), np.max([tr.sigma_q for tr in trajs], 0))
    sq = []
    for tr in trajs:
        hi = len(tr) - horizon - 1
        for st in (np.linspace(tr.window, hi, STARTS).astype(int) if hi > tr.window else ()):
            act = native.activation_at(m, system.columns, tr.q[st], tr.ctrl[st])[0] if m.na else None
            mujoco.mj_resetData(m, d)
            pred = native.rollout(m, d, tr, st, horizon, system.substeps, tr.q[st], tr.v[st], act=act)
            e = (pred - tr.q[st + 1: st + 1 + horizon]) / spread
            sq.append(1e6 if native.unstable(d) or not np.all(np.isfinite(e)) else float(np.mean(e ** 2)))
    return float(np.sqrt(np.mean(sq))) if sq else float("nan")


def logged_units(system, z, trajs, horizon: int) -> str:
    """A sentence naming the joints whose recordings the nominal model ``z`` predicts at least
    ``GAIN`` times better read in another unit (``OTHER``; ``prediction_error`` over ``horizon``
    samples), or "" where none do.

    Tried, for each reading (``OTHER``: another unit, the sign flipped, the zero half a turn
    away): every hinge and slide alone, all hinges, all slides, all of both (a logger writes every
    angle alike), each with and without its servos' commands read alike (a velocity servo's
    command scaled, not offset); the largest group that passes is named."""
    m = system.mj
    native_m = to_mjmodel(system.physics, z)  # (one model for every reading: only the data change)
    base = prediction_error(system, native_m, trajs, horizon)
    if not np.isfinite(base):
        return ""
    by_type = {t: [j for j in range(m.njnt) if int(m.jnt_type[j]) == t] for t in OTHER}
    best = None  # (joints, reading, ratio, servos read alike)
    for reading in range(max(len(r) for r in OTHER.values())):
        types = {t: js for t, js in by_type.items() if reading < len(OTHER[t])}
        every = [j for js in types.values() for j in js]
        groups = [[j] for j in every] + [js for js in types.values() if len(js) > 1]
        if every and len(every) > max(len(js) for js in types.values()):
            groups.append(every)
        for group in groups:
            qa, da = [int(m.jnt_qposadr[j]) for j in group], [int(m.jnt_dofadr[j]) for j in group]
            s, c = (np.array([OTHER[int(m.jnt_type[j])][reading][k] for j in group]) for k in (0, 1))
            servos = _servos(m, group)
            for acts in ([[]] + ([servos] if servos else [])):
                at = [group.index(actuator_joint(m, a)) for a in acts]
                held = np.array([is_servo(m, a) for a in acts], bool)  # (a position's setpoint: offset too)
                read = [_scaled(t, qa, da, s, c, acts, s[at], np.where(held, c[at], 0.0)) for t in trajs]
                ratio = prediction_error(system, native_m, read, horizon) / base
                if ratio * GAIN <= 1.0 and (best is None or (len(group), -ratio) > (len(best[0]), -best[2])):
                    best = (group, reading, ratio, acts)
    if best is None:
        return ""
    group, reading, ratio, acts = best
    servos = ", the servos' commands" if acts else ""
    cols = ", ".join(f"qpos:{system.joints[j]} {OTHER[int(m.jnt_type[j])][reading][2]}" for j in group)
    return (f"the recordings may be logged in other units or conventions than the model's (radians, metres, its "
            f"joint axes and zeros): read {cols} (and their velocities{servos}), the model predicts them "
            f"{1 / ratio:.3g}x better -- if so, convert the columns (or the model's axis, zero or gear) and run again")


def force_units(names: list[str], measured: np.ndarray, predicted: np.ndarray) -> str:
    """A sentence naming the ``force:`` columns that match the model's actuator force only after a
    factor far from 1 (another unit: a motor's current in A logged for its torque in N m, a torque
    before the gear), or "" where none do.

    ``measured``, ``predicted``: ``[..., nu]`` the recorded force and the kept model's prediction
    of it on the same samples. A column is named where its least-squares factor is off 1 by 2x or
    more, leaves at most ``1 / GAIN`` of the column's error without it, and at most ``SHAPE`` of
    its mean square: the scaled prediction has the column's shape (a force limit the model lacks
    changes the shape: a clip at a fifth of a sine's amplitude, fitted by a factor 0.25, leaves 13%)."""
    f, p = measured.reshape(-1, measured.shape[-1]), predicted.reshape(-1, predicted.shape[-1])
    ok = np.all(np.isfinite(f) & np.isfinite(p), axis=1)
    f, p = f[ok], p[ok]
    said = []
    for a, name in enumerate(names):
        pp = float(p[:, a] @ p[:, a])
        if pp <= 0:
            continue
        k = float(f[:, a] @ p[:, a]) / pp
        before, after = np.mean((f[:, a] - p[:, a]) ** 2), np.mean((f[:, a] - k * p[:, a]) ** 2)
        if (abs(k) > 0 and abs(np.log(abs(k))) >= np.log(2.0) and after * GAIN <= before
                and after <= SHAPE * np.mean(f[:, a] ** 2)):
            said.append(f"{name} reads {k:.4g}x the model's actuator force")
    if not said:
        return ""
    return ("the measured forces may be logged in other units than the model's actuator force (N, N m): "
            + "; ".join(said) + " (a motor's current for its torque, a torque before its gear?) -- if so, scale the "
              "columns and run again")
