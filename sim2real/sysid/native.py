"""Native MuJoCo replays of a recording's commands (``mj_step``, no JAX): the short predictions the
checks before and after a diagnosis need from the model as it is -- the prediction horizon and
the noise of rough motion (``diagnose``), the units a recording was logged in (``units``)."""
from __future__ import annotations

import contextlib

import mujoco
import numpy as np

_UNSTABLE = [int(w) for w in (mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQVEL,
                              mujoco.mjtWarning.mjWARN_BADQPOS)]


@contextlib.contextmanager
def quiet():
    """MuJoCo's warnings (a diverged step: "Nan, Inf or huge value in QACC") not printed nor
    appended to ``MUJOCO_LOG.TXT`` in the working folder: a replay from a state the model cannot
    follow is expected to diverge, and ``unstable`` counts it instead."""
    before = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda msg: None)
    try:
        yield
    finally:
        mujoco.set_mju_user_warning(before)


def unstable(d: mujoco.MjData) -> bool:
    """Whether a step since ``d`` was last reset diverged (MuJoCo then resets the state and goes on)."""
    return any(d.warning[w].number for w in _UNSTABLE)


def activation_at(m: mujoco.MjModel, columns, q, ctrl) -> tuple[np.ndarray, np.ndarray]:
    """The actuators' activations ``[na]`` at rest in state ``q [nq]`` under command ``ctrl [nu]``,
    and how they move with the joints' positions there ``[na, nq]`` (``columns``: the model's
    ``trajectory.ModelColumns``). An integrating servo holds its joint (or tendon) where it is:
    its setpoint is the actuator's length there (gear x joint position for a joint); a filter is
    at rest under the command."""
    act, dact, d = np.zeros(m.na), np.zeros((m.na, m.nq)), None
    for a in range(m.nu):
        adr = m.actuator_actadr[a]
        if adr < 0:
            continue
        if m.actuator_dyntype[a] == mujoco.mjtDyn.mjDYN_INTEGRATOR:
            if d is None:
                d = mujoco.MjData(m)
                d.qpos[:] = q
                mujoco.mj_forward(m, d)
                moment = np.zeros((m.nu, m.nv))
                mujoco.mju_sparse2dense(moment, d.actuator_moment, d.moment_rownnz, d.moment_rowadr, d.moment_colind)
            if m.actuator_biasprm[a, 1] != 0:   # (the moment [nv] on the positions' columns [nq])
                act[adr] = d.actuator_length[a]
                dact[adr, columns.same_q] = moment[a, columns.same_v]
        else:
            act[adr] = ctrl[a]
    return act, dact


def rollout(m: mujoco.MjModel, d: mujoco.MjData, tr, s: int, steps: int, substeps: int, qpos, qvel,
            with_qvel: bool = False, act=None):
    """Positions ``[steps, nq]`` (and velocities: ``[steps, nq + nv]`` ``with_qvel``) of the native
    model from state ``(qpos, qvel)`` (and activations ``act [na]``, else 0) at sample ``s`` of
    ``tr`` through its recorded commands (``substeps`` physics steps per sample); NaN past its end."""
    d.qpos[:], d.qvel[:] = qpos, qvel
    if m.na:
        d.act[:] = 0.0 if act is None else act
    q = np.full((steps, m.nq + (m.nv if with_qvel else 0)), np.nan)
    with quiet():
        for k in range(min(steps, len(tr) - s - 1)):
            d.ctrl[:] = tr.ctrl[s + k]
            d.qfrc_applied[:] = tr.qfrc[s + k]
            for _ in range(substeps):
                mujoco.mj_step(m, d)
            q[k, : m.nq] = d.qpos
            if with_qvel:
                q[k, m.nq:] = d.qvel
    return q
