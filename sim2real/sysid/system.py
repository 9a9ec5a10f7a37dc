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


# (a site's: a thruster, a propeller, a Cartesian servo with a reference site; MJX computes its moment
# arms as MuJoCo does, so the command path acts on it as on a tendon's: ``kinds.base.actuator_joint``)
_TRANSMISSIONS = (int(mujoco.mjtTrn.mjTRN_JOINT), int(mujoco.mjtTrn.mjTRN_JOINTINPARENT), int(mujoco.mjtTrn.mjTRN_TENDON),
                  int(mujoco.mjtTrn.mjTRN_SITE))


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
                             "actuators on joints, tendons and sites only")
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


def _geom_label(m: mujoco.MjModel, g: int) -> str:
    shape = mujoco.mjtGeom(int(m.geom_type[g])).name.removeprefix("mjGEOM_").lower()
    body = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[g])) or f"body #{m.geom_bodyid[g]}"
    return f"{shape} '{mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or f'#{g}'}' of {body}"


def _body_pair(m: mujoco.MjModel, g1: int, g2: int) -> tuple[int, int]:
    """The ids of the bodies of geoms ``g1`` and ``g2``, in order (an exclusion's key)."""
    return tuple(sorted((int(m.geom_bodyid[g1]), int(m.geom_bodyid[g2]))))


def _contact_pairs(m: mujoco.MjModel) -> list[tuple[int, int, int]]:
    """The geom pairs MJX collides at every physics step, whether or not they touch: ``(geom1,
    geom2, declared pair id or -1)`` (MJX's own filter: the pairs ``mjx.put_model`` checks)."""
    from mujoco.mjx._src import collision_driver as cd

    return [(int(g1), int(g2), int(ip)) for g1, g2, ip in cd.geom_pairs(m)]


def _leave_out_contacts(m: mujoco.MjModel, xml_path: str, notes: list[str], apart=()):
    """``m`` with contacts left out of the simulation, and the geom pairs left out that MJX cannot
    collide ``[(g1, g2)]`` (``check_recording_covers`` refuses a recording in which they touch).

    Left out are the bodies (an ``<exclude>`` of the two, which leaves out every geom pair between
    them) of (a) a pair of shapes MJX has no collision function for (a cylinder and a box, in MuJoCo
    4.0), for which ``mjx.put_model`` refuses the whole model although most arms never bring
    those links together; a declared ``<pair>`` of them is the user's word that they touch, and is
    refused; and (b) ``apart``: body-id pairs no recorded pose brings near (``bodies_apart``).
    Why (b): MJX collides every candidate pair and carries its contacts through the constraint
    solver at every step, touching or not: a 6-joint arm with 19 contact slots ran 15x slower."""
    from mujoco.mjx._src import collision_driver as cd

    pairs = _contact_pairs(m)
    bad = [(g1, g2, ip) for g1, g2, ip in pairs if not cd.has_collision_fn(*m.geom_type[[g1, g2]])]
    for g1, g2, ip in bad:
        if ip >= 0:
            raise ModelError(f"{xml_path}: the contact pair of {_geom_label(m, g1)} and {_geom_label(m, g2)} is declared, "
                             "but MJX cannot collide these shapes; give one of them a sphere, capsule or box")
    unsupported = {_body_pair(m, g1, g2) for g1, g2, _ in bad}
    bodies = sorted(unsupported | {tuple(sorted(p)) for p in apart})
    if not bodies:
        return m, []
    try:
        spec = mujoco.MjSpec.from_file(xml_path)
        for b1, b2 in bodies:
            names = []
            for b in (b1, b2):
                if not spec.bodies[b].name:  # (an exclusion names its bodies)
                    spec.bodies[b].name = f"sim2real_body{b}"
                names.append(spec.bodies[b].name)
            spec.add_exclude(bodyname1=names[0], bodyname2=names[1])
        m2 = spec.compile()
    except Exception as e:
        raise ModelError(f"{xml_path}: leaving the contacts of bodies {bodies} out of the simulation failed ({e})") from None
    if bad:
        notes.append("MJX cannot collide " + "; ".join(f"{_geom_label(m, g1)} with {_geom_label(m, g2)}" for g1, g2, _ in bad)
                     + ": contacts between " + ", ".join(f"'{m2.body(b1).name}' and '{m2.body(b2).name}'"
                                                         for b1, b2 in sorted(unsupported))
                     + " are left out of the simulation (every recorded pose checked: their geoms never touch)")
    left_out = [(g1, g2) for g1, g2, _ in pairs if _body_pair(m, g1, g2) in unsupported]
    return m2, left_out


def _pyramidal_without_contacts(m: mujoco.MjModel) -> None:
    """``m``'s friction cone set pyramidal where no contact of more than one dimension can occur.
    MJX's elliptic-cone solver, run whenever there are constraints (a joint's friction loss, a
    limit), gathers such contacts with an index array that is empty -- and so of float type --
    where there are none, and fails at the first step ("Indexer must have integer or boolean
    type"): Menagerie's SO-ARM100 (``cone="elliptic"``, friction loss on every joint), every
    contact left out because no recorded pose brings its links near. Without such contacts the
    cone changes nothing; ``fitted.xml`` keeps the model's (export reads the file)."""
    if m.opt.cone != mujoco.mjtCone.mjCONE_ELLIPTIC:
        return
    dims = [int(m.pair_dim[ip]) if ip >= 0 else int(max(m.geom_condim[g1], m.geom_condim[g2]))
            for g1, g2, ip in _contact_pairs(m)]
    if not any(d > 1 for d in dims):
        m.opt.cone = mujoco.mjtCone.mjCONE_PYRAMIDAL


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
      apart: body-id pairs whose contacts are left out of the simulation (``bodies_apart``).
      left_out_contacts: the geom pairs MJX cannot collide, left out (``_leave_out_contacts``).
      unlimited: joint ids whose range limits are left out of the simulation (``limits_clear``).
    """

    def __init__(self, xml_path: str, dt: float | None = None, coulomb_eps: float = 1e-3, max_delay: int = 8,
                 refit_gains: bool = False, substeps: int | None = None, mass_above: float = 0.0,
                 apart: tuple = (), unlimited: tuple = ()):
        m = _load(xml_path)
        self.xml_path = xml_path
        self.mass_above = float(mass_above)
        self.notes: list[str] = []
        check_model(m, xml_path)
        m, self.left_out_contacts = _leave_out_contacts(m, xml_path, self.notes, apart)
        _pyramidal_without_contacts(m)
        self.unlimited = tuple(int(j) for j in unlimited)
        m.jnt_limited[list(self.unlimited)] = 0  # (``limits_clear`` says why; fitted.xml keeps them: export reads the file)
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
        """Every joint must be measured (``trajectory.ModelColumns``); and where contacts were left
        out of the simulation that MJX cannot collide (``_leave_out_contacts``), no recorded pose may bring
        their geoms together (within their margins)."""
        self.columns.check_recording_covers(rec)
        if not self.left_out_contacts:
            return
        m = self.mj
        for k, d in self._poses(rec):
            for g1, g2 in self.left_out_contacts:
                reach = float(m.geom_margin[g1] + m.geom_margin[g2])
                if (dist := mujoco.mj_geomDistance(m, d, g1, g2, reach + 0.01, None)) <= reach:
                    raise ModelError(
                        f"{rec.path}: at data row {rec.first_row + k} (t = {rec.time[k]:.4g} s) {_geom_label(m, g1)} "
                        f"touches {_geom_label(m, g2)} (distance {dist:.3g} m), and MJX cannot collide these shapes; give "
                        "one of them a sphere, capsule or box in the model")

    def _poses(self, rec):
        """Each recorded pose of ``rec``: ``(row, MjData)``, the bodies and geoms placed (one MjData, reused)."""
        d = mujoco.MjData(self.mj)
        for k, q in enumerate(self.columns.arrays(rec)[0]):
            d.qpos[:] = q
            mujoco.mj_kinematics(self.mj, d)
            yield k, d

    def bodies_apart(self, recs, reach: float = 0.01) -> tuple[tuple[tuple[int, int], ...], str]:
        """The body-id pairs whose geoms MJX would collide at every step but no pose of ``recs``
        brings within ``reach`` (m) of each other, beyond their margins and the most their distance
        changes between two samples (what the motion between samples could close), and a note
        saying so (``System(apart=...)`` leaves their contacts out). A body pair with one geom
        pair near, or a declared ``<pair>``, keeps all its contacts."""
        pairs = [(g1, g2) for g1, g2, ip in _contact_pairs(self.mj) if ip < 0]
        if not pairs:
            return (), ""
        m = self.mj
        g1s, g2s = (np.array(x) for x in zip(*pairs))
        closest, change = np.full(len(pairs), np.inf), np.zeros(len(pairs))
        for rec in recs:
            prev = None
            for _, d in self._poses(rec):
                dist = np.array([mujoco.mj_geomDistance(m, d, g1, g2, 1.0, None) for g1, g2 in pairs])
                closest = np.minimum(closest, dist)
                if prev is not None:
                    change = np.maximum(change, np.abs(dist - prev))
                prev = dist
        need = m.geom_margin[g1s] + m.geom_margin[g2s] + reach + change
        key = [_body_pair(m, a, b) for a, b in pairs]
        near = {k for k, c, n in zip(key, closest, need) if c <= n}
        apart = tuple(sorted(set(key) - near))
        if not apart:
            return (), ""
        gap = min(c - n for k, c, n in zip(key, closest, need) if k in apart)
        return apart, (f"contacts of {len(apart)} of {len(set(key))} body pairs left out of the simulation: no "
                       f"recorded pose brings their geoms within {reach:g} m of each other, beyond their margins and "
                       f"what one sample's motion could close (the least room left {gap:.3g} m; "
                       + ", ".join(f"'{self.bodies[a] or a}'-'{self.bodies[b] or b}'" for a, b in apart)
                       + "), and MJX would collide each pair at every step")

    def limits_clear(self, recs, share: float = 0.1) -> tuple[tuple[int, ...], str]:
        """The limited hinges and slides whose range no recorded position comes near: every sample
        of ``recs`` stays further than ``share`` of the range's span from both ends, beyond the
        joint's margin and the most its position changes between two samples; and a note saying
        so (``System(unlimited=...)`` leaves their limits out). Why: MJX carries every limited
        joint through the constraint solver at every step, reached or not (a 6-joint arm whose
        motion never nears its ranges: 161 s with them, 93 s without, the same diagnosis;
        ``new_user_probes/eleventh_wave.txt``), and a limit never reached exerts no force: the
        predictions of the recordings are the same without it."""
        m = self.mj
        lim = [j for j in self.one_dof if m.jnt_limited[j]]
        if not lim:
            return (), ""
        adr = np.array([m.jnt_qposadr[j] for j in lim])
        lo, hi = m.jnt_range[lim, 0], m.jnt_range[lim, 1]
        room = np.full(len(lim), np.inf)
        step = np.zeros(len(lim))
        for rec in recs:
            q = self.columns.arrays(rec)[0][:, adr]
            room = np.minimum(room, np.minimum(q.min(0) - lo, hi - q.max(0)))
            if len(q) > 1:
                step = np.maximum(step, np.abs(np.diff(q, axis=0)).max(0))
        need = share * (hi - lo) + m.jnt_margin[lim] + step
        clear = tuple(int(j) for j, r, n in zip(lim, room, need) if r > n)
        if not clear:
            return (), ""
        jn = self.columns.joints
        return clear, (f"the range limits of {len(clear)} of {len(lim)} limited joints left out of the simulation "
                       f"({', '.join(jn[j] for j in clear)}): no recorded position comes within {share:g} of the "
                       "range's span of either end, beyond the joint's margin and one sample's motion, and MJX "
                       "would carry each limit through the constraint solver at every step (fitted.xml keeps them)")

    def arrays(self, rec):
        """Recording -> model-order arrays (``trajectory.ModelColumns.arrays``)."""
        return self.columns.arrays(rec)
