"""A user's MJCF as the subject of identification: named parameters, native and MJX models.

The parameter spec has the *nominal* parameters a model writer sets (body masses, declared joint
damping and friction loss, actuator gains) and every effect of the library on every joint,
actuator and body, all neutral by default, so the nominal model is ``spec.default`` and a
fitted model is another ``z``. The plant is the one the envs step (``physics/plant.py``:
``PhysicsModel.apply`` + ``Effects``, stepped by ``stepper.advance``), at the recordings' sample period.

What MJX cannot run as written is changed here, and said in ``notes``: the ``implicit`` and
``RK4`` integrators (and Euler without implicit damping) run as ``implicitfast``, whose implicit
damping the Coulomb model relies on; a declared ``frictionloss`` becomes the effects library's
Coulomb level (a nominal parameter, re-fitted like the masses); the constraint solver is capped
at 10 iterations.
"""
from __future__ import annotations

import dataclasses
import os

import mujoco
import numpy as np

from sim2real.physics import catalog, kinds
from sim2real.physics.kinds.lag import shared_param as shared_lag_param
from sim2real.physics.params import Param
from sim2real.physics.plant import Plant
from sim2real.sysid.trajectory import ModelColumns


ONE_DOF = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
# what a ball joint has of the joint-level effects: Coulomb friction and viscous damping (the same
# on each of its three dofs), the parameters their plug-ins own
BALL_EFFECTS = ("coulomb_friction", "viscous_damping")
BALL_KINDS = tuple(k for kind in kinds.all_kinds() if kind.effect in BALL_EFFECTS for k in kind.owns)


class ModelError(ValueError):
    """An MJCF the diagnosis tool cannot use; the message says why."""


def _names(m, obj, n):
    return [mujoco.mj_id2name(m, obj, i) for i in range(n)]


_INTEGRATOR = {int(mujoco.mjtIntegrator.mjINT_EULER): "Euler", int(mujoco.mjtIntegrator.mjINT_RK4): "RK4",
               int(mujoco.mjtIntegrator.mjINT_IMPLICIT): "implicit",
               int(mujoco.mjtIntegrator.mjINT_IMPLICITFAST): "implicitfast"}


_TRANSMISSIONS = (int(mujoco.mjtTrn.mjTRN_JOINT), int(mujoco.mjtTrn.mjTRN_JOINTINPARENT), int(mujoco.mjtTrn.mjTRN_TENDON))


def check_model(m: mujoco.MjModel, xml_path: str) -> None:
    """Refuse what the diagnosis cannot handle, naming the joint or actuator."""
    jn = _names(m, mujoco.mjtObj.mjOBJ_JOINT, m.njnt)
    for j in range(m.njnt):
        if not jn[j]:
            raise ModelError(f"{xml_path}: joint #{j} has no name; name every joint (recordings refer to them)")
    for a in range(m.nu):
        an = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a)
        if not an:
            raise ModelError(f"{xml_path}: actuator #{a} has no name; name every actuator")
        if int(m.actuator_trntype[a]) not in _TRANSMISSIONS:
            kind = mujoco.mjtTrn(m.actuator_trntype[a]).name.removeprefix("mjTRN_").lower()
            raise ModelError(f"{xml_path}: actuator '{an}' has a {kind} transmission; the diagnosis handles "
                             "actuators on joints and tendons only")
        if int(m.actuator_dyntype[a]) in (int(mujoco.mjtDyn.mjDYN_MUSCLE), int(mujoco.mjtDyn.mjDYN_USER)):
            raise ModelError(f"{xml_path}: actuator '{an}': muscle/user dynamics are not supported")


def _load(xml_path: str) -> mujoco.MjModel:
    if not os.path.exists(xml_path):
        raise ModelError(f"model file '{xml_path}' not found")
    if os.path.isdir(xml_path):
        raise ModelError(f"model '{xml_path}' is a folder, not an MJCF file")
    try:
        return mujoco.MjModel.from_xml_path(xml_path)
    except Exception as e:  # mujoco raises ValueError with the parser's message
        raise ModelError(f"{xml_path}: cannot compile the MJCF: {e}") from None


class System:
    """Static structure for identification of one MJCF at one sample period.

    Attributes:
      mj: native model as the diagnosis simulates it (timestep ``h``, integrator MJX supports).
      spec: nominal + effect parameters.
      physics, effects: the MJX ``apply`` and the effects library for this model.
      joints, actuators, bodies: names (``bodies``: every body, index = body id).
      nominal: names of the nominal parameters a fit re-estimates (masses, declared damping and
        friction loss; actuator gains anchor the force scale and stay as declared).
      substeps, h: physics steps per sample and their length (s).
      notes: what was changed to simulate the model, in words.
      mass_above: a body's re-fitted mass may rise to this many times the model's (0: to the
        mass kind's own bound, 1e3 times); the diagnosis sets it where a payload is searched
        (``DiagnoseConfig.mass_above``).
    """

    def __init__(self, xml_path: str, dt: float | None = None, coulomb_eps: float = 1e-3, max_delay: int = 8,
                 refit_gains: bool = False, substeps: int | None = None, mass_above: float = 0.0):
        m = _load(xml_path)
        self.xml_path = xml_path
        self.mass_above = float(mass_above)
        self.notes: list[str] = []
        check_model(m, xml_path)
        self.columns = ModelColumns(m, xml_path)
        jn = self.columns.joints
        self._adapt(m, dt, substeps)
        self.joints = jn
        # [nq]: the position columns that are angles (a hinge's; a quaternion's components are not)
        self.angles = np.zeros(m.nq, bool)
        self.angles[[m.jnt_qposadr[j] for j in range(m.njnt) if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]] = True
        # joint-level effects and declared damping are parameters of one-dof joints (hinges, slides);
        # a ball joint's friction and damping too (the same level on its three dofs, as MuJoCo's
        # own); a free joint (a floating base) is simulated and measured, its physics as declared
        self.one_dof = [j for j in range(m.njnt) if int(m.jnt_type[j]) in ONE_DOF]
        self.balls = [j for j in range(m.njnt) if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_BALL)]
        self.qpos_names, self.dof_names = self.columns.qpos_names, self.columns.dof_names
        self.actuators = self.columns.actuators
        self.bodies = _names(m, mujoco.mjtObj.mjOBJ_BODY, m.nbody)
        moving = [b for b in range(1, m.nbody) if m.body_mass[b] > 0 and self._moves(m, b)]
        params: list[Param] = catalog.body_mass_params(m, moving)
        if mass_above:
            params = [dataclasses.replace(p, high=mass_above * p.default) for p in params]
        declared_fl = {}
        for j in sorted(self.one_dof + self.balls):
            d = float(m.dof_damping[m.jnt_dofadr[j]])
            unit = "N s/m" if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE else "Nm s/rad"
            if d > 0:  # declared damping is a nominal parameter; undeclared is an effect (viscous)
                params.append(Param(f"damping:{jn[j]}", d, 0.0, 100 * d + 1.0, unit,
                                    "declared joint damping", "dof_damping", j))
            fl = float(m.dof_frictionloss[m.jnt_dofadr[j]])
            if fl > 0:
                declared_fl[j] = fl
        params += catalog.actuator_gain_params(m, range(m.nu))
        effect = catalog.effect_params(m, self.one_dof, range(m.nu), moving)
        effect += [p for p in catalog.effect_params(m, self.balls, (), ()) if p.kind in BALL_KINDS]
        for i, p in enumerate(effect):  # a declared frictionloss is the Coulomb model's nominal level
            if p.kind == "coulomb" and p.index in declared_fl:
                effect[i] = Param(p.name, round(declared_fl[p.index], 9), p.low, max(p.high, 100 * declared_fl[p.index]),
                                  p.unit, "declared friction loss (Coulomb level)", "coulomb", p.index)
        params += effect
        params += catalog.payload_position_params(m, moving)
        params += catalog.contact_friction_params(m, moving)
        params += catalog.armature_params(m, self.one_dof)
        params += catalog.backlash_motor_side_params(m, range(m.nu))
        if m.nu >= 2:  # one lag shared by every actuator (searched when asked for: kinds/lag.py)
            params.append(shared_lag_param())
        if declared_fl:
            m.dof_frictionloss[:] = 0.0
            self.notes.append("declared frictionloss (" + ", ".join(f"{jn[j]} {v:g}" for j, v in declared_fl.items())
                              + ") is simulated as the effects library's Coulomb friction and re-fitted")
        # the plant the envs step (physics/plant.py), at the recordings' sample period
        self.plant = Plant(m, params, max_delay, coulomb_eps)
        self.spec, self.physics, self.effects = self.plant.spec, self.plant.physics, self.plant.effects
        self.mj, self.data0 = self.plant.mj, self.plant.data0
        # Positions and commands alone identify forces only up to a common scale (scaling every
        # mass, damping and gain together leaves the motion unchanged), so something must anchor
        # the scale: the actuator gains (known from the drive's datasheet) by default.
        kinds = ("body_mass", "dof_damping") + (("actuator_gain", "actuator_kv") if refit_gains else ())
        self.nominal = [p.name for p in params if p.kind in kinds or
                        (p.kind == "coulomb" and p.index in declared_fl)]

    def _adapt(self, m: mujoco.MjModel, dt: float | None, substeps: int | None = None) -> None:
        """Integrator, timestep and solver settings MJX can run (``notes`` says what changed)."""
        integ = _INTEGRATOR.get(int(m.opt.integrator), "?")
        eulerdamp_off = bool(m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_EULERDAMP)
        if integ in ("implicit", "RK4") or (integ == "Euler" and eulerdamp_off):
            m.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
            self.notes.append(f"the {integ} integrator{' without implicit damping' if eulerdamp_off else ''} is "
                              "simulated as implicitfast (MJX supports it, and it treats damping -- and so the "
                              "Coulomb friction model -- implicitly)")
        self.h_model = float(m.opt.timestep)
        self.substeps, self.h = 1, self.h_model
        if dt is not None:
            self.substeps = int(substeps) if substeps else max(1, int(round(dt / self.h_model)))
            self.h = dt / self.substeps
            if abs(self.h - self.h_model) > 0.01 * self.h_model:
                self.notes.append(f"simulated at {self.h * 1e3:.4g} ms steps ({self.substeps} per sample of "
                                  f"{dt * 1e3:.4g} ms) instead of the model's {self.h_model * 1e3:.4g} ms"
                                  + ((" (a finer step converged; the physics found does not depend on the step)"
                                      if self.h < self.h_model else
                                      " (doubled while its predictions stay within a tenth of the noise of the model's step's)")
                                     if substeps else ""))
            m.opt.timestep = self.h
        if m.opt.iterations > 10 or m.opt.ls_iterations > 10:
            m.opt.iterations, m.opt.ls_iterations = min(m.opt.iterations, 10), min(m.opt.ls_iterations, 10)

    @staticmethod
    def _moves(m: mujoco.MjModel, b: int) -> bool:
        """The body or one of its ancestors has a joint."""
        while b > 0:
            if m.body_jntnum[b] > 0:
                return True
            b = int(m.body_parentid[b])
        return False

    @property
    def nq(self) -> int:
        return int(self.mj.nq)

    @property
    def force_known(self) -> bool:
        """Whether the recordings' commands apply a known force (the model has an actuator). Without
        one (a free swing) positions fix forces only up to a common scale: every mass, payload and
        dissipation scaled together moves the bodies alike, so that direction is unidentifiable and
        fitted values are relative to the nominal masses (the fits, the force-scale finding and the
        report's notes all ask this)."""
        return int(self.mj.nu) > 0

    def declared_damping(self, joint: str) -> bool:
        return f"damping:{joint}" in self.spec

    def declared_friction(self, joint: str) -> bool:
        return f"coulomb:{joint}" in self.nominal

    def check_recording_covers(self, rec) -> None:
        """Every joint must be measured (``trajectory.ModelColumns``)."""
        self.columns.check_recording_covers(rec)

    def arrays(self, rec):
        """Recording -> model-order arrays (``trajectory.ModelColumns.arrays``)."""
        return self.columns.arrays(rec)
