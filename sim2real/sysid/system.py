"""A user's MJCF as the subject of identification: named parameters, native and MJX models.

The parameter spec has the *nominal* parameters a model writer sets (body masses, joint damping,
actuator gains) and every effect of the library on every joint, actuator and body, all neutral
by default, so the nominal model is ``spec.default`` and a fitted model is another ``z``.
"""
from __future__ import annotations

import os

import mujoco
import numpy as np
from mujoco import mjx

from sim2real.physics import catalog
from sim2real.physics.effects import Effects, EffectsConfig
from sim2real.physics.model_apply import PhysicsModel
from sim2real.physics.params import Param, ParamSpec


class ModelError(ValueError):
    """An MJCF the diagnosis tool cannot use; the message says why."""


def _names(m, obj, n):
    return [mujoco.mj_id2name(m, obj, i) for i in range(n)]


class System:
    """Static structure for identification of one MJCF.

    Attributes:
      mj: native model (with the saturation clamp structure, see ``PhysicsModel``).
      spec: nominal + effect parameters.
      physics, effects: the MJX ``apply`` and the effects library for this model.
      joints, actuators, bodies: names.
      nominal: names of the nominal parameters a fit may re-estimate (masses and declared damping;
        actuator gains too with ``refit_gains``, for systems whose gravity load anchors the scale).
    """

    def __init__(self, xml_path: str, coulomb_eps: float = 1e-3, max_delay: int = 8, refit_gains: bool = False):
        if not os.path.exists(xml_path):
            raise ModelError(f"model file '{xml_path}' not found")
        try:
            m = mujoco.MjModel.from_xml_path(xml_path)
        except Exception as e:  # mujoco raises ValueError with the parser's message
            raise ModelError(f"{xml_path}: cannot compile the MJCF: {e}") from None
        self.xml_path = xml_path
        for j in range(m.njnt):
            if int(m.jnt_type[j]) not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
                raise ModelError(f"{xml_path}: joint '{_names(m, mujoco.mjtObj.mjOBJ_JOINT, m.njnt)[j]}' is not a "
                                 "hinge or slide; the diagnosis tool handles hinge/slide joints only")
        if m.nu == 0:
            raise ModelError(f"{xml_path}: the model has no actuators; commands cannot be replayed")
        for a in range(m.nu):
            if m.actuator_trntype[a] != mujoco.mjtTrn.mjTRN_JOINT:
                raise ModelError(f"{xml_path}: actuator #{a} does not drive a joint directly")
        self.joints = _names(m, mujoco.mjtObj.mjOBJ_JOINT, m.njnt)
        self.actuators = _names(m, mujoco.mjtObj.mjOBJ_ACTUATOR, m.nu)
        bodies = [b for b in range(1, m.nbody) if m.body_mass[b] > 0]
        self.bodies = _names(m, mujoco.mjtObj.mjOBJ_BODY, m.nbody)
        params: list[Param] = catalog.body_mass_params(m, bodies)
        for j in range(m.njnt):
            d = float(m.dof_damping[m.jnt_dofadr[j]])
            if d > 0:  # declared damping is a nominal parameter; undeclared is an effect (viscous)
                unit = "N s/m" if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE else "Nm s/rad"
                params.append(Param(f"damping:{self.joints[j]}", d, 0.0, 100 * d + 1.0, unit,
                                    "declared joint damping", "dof_damping", j))
        params += catalog.actuator_gain_params(m, range(m.nu))
        params += catalog.effect_params(m, range(m.njnt), range(m.nu), bodies)
        params += catalog.common_params(m, max_delay)
        self.spec = ParamSpec(params)
        # Positions and commands alone identify forces only up to a common scale (scaling every
        # mass, damping and gain together leaves the motion unchanged), so something must anchor
        # the scale: the actuator gains (known from the drive's datasheet) by default.
        kinds = ("body_mass", "dof_damping") + (("actuator_gain", "actuator_kv") if refit_gains else ())
        self.nominal = [p.name for p in params if p.kind in kinds]
        self.physics = PhysicsModel(m, self.spec)
        self.mj = self.physics.mj
        self.effects = Effects(self.mj, self.spec, EffectsConfig(max_delay=max_delay, coulomb_eps=coulomb_eps))
        self.data0 = mjx.make_data(self.physics.mx)

    @property
    def rk4(self) -> bool:
        return int(self.mj.opt.integrator) == int(mujoco.mjtIntegrator.mjINT_RK4)

    @property
    def nq(self) -> int:
        return int(self.mj.nq)

    def declared_stiffness(self, joint: str) -> bool:
        return float(self.mj.jnt_stiffness[self.joints.index(joint)]) > 0

    def declared_damping(self, joint: str) -> bool:
        return f"damping:{joint}" in self.spec

    def check_recording_covers(self, rec) -> None:
        """Every joint must be measured (the state is set from the data)."""
        missing = [j for j in self.joints if rec.get("qpos", j) is None]
        if missing:
            from sim2real.sysid.recordings import RecordingError

            raise RecordingError(f"{rec.path}: no qpos column for joint(s) {', '.join(missing)} of the model "
                                 f"({self.xml_path}); every joint's position must be recorded")

    def arrays(self, rec):
        """Recording -> ``(qpos [T, nq], ctrl [T, nu], force [T, nu] or None, qfrc [T, nv])`` in model order."""
        self.check_recording_covers(rec)
        T = len(rec)
        qpos = np.stack([rec.get("qpos", j) for j in self.joints], -1)
        ctrl = np.stack([rec.get("ctrl", a) for a in self.actuators], -1)
        force = None
        if all(rec.get("force", a) is not None for a in self.actuators):
            force = np.stack([rec.get("force", a) for a in self.actuators], -1)
        qfrc = np.zeros((T, self.mj.nv))
        for j, name in enumerate(self.joints):
            col = rec.get("qfrc", name)
            if col is not None:
                qfrc[:, self.mj.jnt_dofadr[j]] = col
        return qpos, ctrl, force, qfrc
