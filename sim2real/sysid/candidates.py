"""The candidate missing-physics effects the diagnosis searches, with their search grids.

Each candidate is an effect of the simulator's effects library attached to one joint, actuator
or body (or global), described by the physics parameters it sets; each kind's plug-in
(``physics/kinds/``) says which hypotheses it offers and over what grid. Every candidate is screened on
a small grid of its own magnitude (``grid``: simulated at each point, the nominal parameters
re-solved linearly), then the best are fitted by Gauss-Newton on the simulation error.

=====================  ==========  ==========================================================
effect                 attached    parameters (spec names)
=====================  ==========  ==========================================================
coulomb_friction       joint       ``coulomb``, ``coulomb_vel`` (the speed over which it builds up)
                                   (+ ``coulomb_asym``: a level per direction)
viscous_damping        joint       ``viscous`` (only where the MJCF declares no damping)
joint_stiffness        joint       ``stiffness`` (added to a declared spring: then either sign)
sensor_offset          joint       ``sensor_offset``
mass_offset            body        ``payload`` and ``payload_r`` (a point mass along the link; on a
                                   free or ball joint's body, one hinged through its centre of
                                   mass or one welded to a moving body, ``payload_x/y/z``, its
                                   place in the body)
contact_friction       body        ``contact_friction`` (the sliding friction of its contacts; bodies
                                   that touch something in the recordings; only when asked for)
rotor_inertia          joint       ``armature`` (a geared rotor's inertia; only when asked for, and in
                                   place of a named backlash: ``SelectConfig.rotor``)
action_delay           global      ``action_delay`` (samples, fractional)
motor_lag              actuator    ``motor_lag`` (time constant, s)
motor_lag_all          global      ``motor_lag_all`` (one time constant for every actuator; models
                                   with 2+ actuators; searched only when asked for)
actuator_saturation    actuator    ``saturation`` (force limit, actuator force units)
backlash               actuator    ``backlash`` (dead band width, joint units), ``backlash_inertia``,
                                   ``backlash_stiffness`` (the mesh's: 0 rigid)
quadratic_drag         joint       ``drag`` (force -c v|v|; searched only when asked for)
torque_offset          joint       ``torque_offset`` (a constant signed force; only when asked for)
=====================  ==========  ==========================================================

Grids are in the system's own scales (``Scales``): the force a joint needs, its speed and
range, the actuator's forces, the sample period. A search that ends at the edge of its range is
widened once (``widen``) before the diagnosis gives up on it.
"""
from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from sim2real.physics import kinds
from sim2real.physics.kinds.base import joint_dofs
from sim2real.sysid.system import BALL_EFFECTS

# (joint, body, global, actuator hypotheses, in the library's order; each from its kind plug-in)
_GROUPS = (kinds.JOINT, kinds.BODY, "", kinds.ACTUATOR)
EFFECTS = ("none",) + tuple(k.effect for g in _GROUPS for k in kinds.offering(g, default_only=True))
"""What the diagnosis searches by default."""
ALL_EFFECTS = ("none",) + tuple(k.effect for g in _GROUPS for k in kinds.offering(g))
"""Everything it can search (``effects=[...]`` may add the rest, e.g. ``quadratic_drag``)."""
SAT_WIDEN = 64  # a saturation that ends at the bottom of its range is searched down to this much lower (``Candidate.widen``)
EDGE = 0.02  # a fitted value within this share of its range's edge ended there
TOUCH_SHARE = 0.02  # a body in contact in fewer of the samples than this cannot show a contact friction


@dataclasses.dataclass(frozen=True)
class Candidate:
    """One hypothesis: ``effect`` at ``target``.

    Attributes:
      params: spec parameters this effect sets (besides the nominal ones).
      grid: screening points, each a tuple of values for ``params``.
      scales: typical magnitude of each parameter (finite-difference steps, standard errors).
      search: range of each parameter the search covers (a fit ending at an edge says so).
      off: the first parameter's value where the effect is absent (0 but for a correction of a
        declared value: a contact friction's is the model's own).
    """

    effect: str
    target: str
    params: tuple
    grid: tuple
    scales: tuple
    search: tuple
    off: float = 0.0

    @property
    def label(self) -> str:
        return self.effect if not self.target else f"{self.effect}@{self.target}"

    def scale_of(self, name: str) -> float:
        return self.scales[self.params.index(name)]

    def is_off(self, v: float) -> bool:
        """The fitted first parameter ``v`` is the effect's own "absent" value (zero friction,
        delay, payload, ...; a saturation at the top of its range): a fit that ends there gained
        nothing from the effect, only from the other parameters it re-fitted."""
        if self.effect == "actuator_saturation":
            return self.at_top(v)
        return abs(v - self.off) <= 1e-3 * self.scales[0]

    def at_top(self, v: float) -> bool:
        """The first parameter ``v`` ended at the top of its search range (within ``EDGE``) or past it."""
        hi = self.search[0][1]
        return v >= ((1 - EDGE) * hi if hi >= 0 else (1 + EDGE) * hi)

    def at_bottom(self, v: float) -> bool:
        """The first parameter ``v`` ended at the bottom of its search range (within ``EDGE``) or below it."""
        lo = self.search[0][0]
        return v <= ((1 + EDGE) * lo if lo >= 0 else (1 - EDGE) * lo)

    def widen(self) -> "Candidate":
        """The same candidate with its (first parameter's) range and grid pushed past the edge."""
        lo, hi = self.search[0]
        pts = [g[0] for g in self.grid]
        if self.effect == "actuator_saturation":  # a limit below the lowest grid point
            # the grid is sized by the nominal model's forces, and where the limit binds the
            # nominal servo asks for far more than it (an integrating one winds up): the beside
            # list's 3846, a 0.086 limit under a grid from 2.3, fitted at 0.099 from any start
            # in [lo/64, lo/2] and not from lo itself (``tuning.md`` step 74). These are the
            # widened fit's starts (``Selector._try``).
            new = tuple((v,) + g[1:] for v, g in zip(np.geomspace(lo / SAT_WIDEN, lo / 2, 4), [self.grid[0]] * 4))
            return dataclasses.replace(self, grid=new, search=((lo / SAT_WIDEN, hi),) + self.search[1:])
        top = max(pts)
        new = tuple((v,) + self.grid[0][1:] for v in np.geomspace(top * 1.5, top * 4, 3))
        return dataclasses.replace(self, grid=new, search=((lo, hi * 4),) + self.search[1:])


@dataclasses.dataclass
class Scales:
    """What sizes the grids: per joint the generalised force it needs (RMS of the nominal inverse
    dynamics), its RMS speed, range and inertia (the mass matrix's diagonal at the mean pose);
    per actuator the 99.5th percentile of its force; the sample period; the longest delay the
    buffer holds (samples); per body whether it touches anything (a contact in at least
    ``TOUCH_SHARE`` of the samples)."""

    force: np.ndarray
    speed: np.ndarray
    range: np.ndarray
    act_force: np.ndarray
    dt: float
    max_delay: int
    inertia: np.ndarray = None
    touch: np.ndarray = None


def actuator_force_scale(act_force: np.ndarray) -> np.ndarray:
    """``[nu]``: each actuator's force scale, the 99.5th percentile of ``|act_force [N, nu]|`` (the
    nominal model's actuator forces along the data; actuator force units, N or N m)."""
    return np.percentile(np.abs(act_force), 99.5, axis=0) if act_force.size else np.zeros(act_force.shape[-1])


def scales_from(system, trajs, act_force: np.ndarray) -> Scales:
    """``act_force [N, nu]``: the nominal model's actuator forces along the data (predicted)."""
    m = system.mj
    d = mujoco.MjData(m)
    q = np.concatenate([t.q for t in trajs])
    v = np.concatenate([t.v for t in trajs])
    a = np.concatenate([t.a for t in trajs])
    keep = np.linspace(0, len(q) - 1, min(len(q), 3000)).astype(int)
    frc = np.empty((len(keep), m.nv))
    touching = np.zeros(m.nbody)
    for i, k in enumerate(keep):
        d.qpos[:], d.qvel[:], d.qacc[:] = q[k], v[k], a[k]
        mujoco.mj_inverse(m, d)
        frc[i] = d.qfrc_inverse
        if d.ncon:  # (mj_inverse found the contacts at this pose)
            touching[np.unique(m.geom_bodyid[d.contact.geom[:d.ncon]])] += 1
    # per joint, over its dofs (a ball joint's three; one for a hinge or slide)
    F = np.array([np.sqrt(np.mean(frc[:, joint_dofs(m, j)] ** 2)) for j in range(m.njnt)])
    af = actuator_force_scale(act_force)
    d.qpos[:] = q.mean(0)
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    I = np.array([M[m.jnt_dofadr[j], m.jnt_dofadr[j]] for j in range(m.njnt)])
    # per joint (its first dof's, its first coordinate's: a hinge's or slide's only one)
    speed = np.array([np.sqrt(np.mean(v[:, joint_dofs(m, j)] ** 2)) for j in range(m.njnt)])
    span = np.ptp(q, 0)[m.jnt_qposadr]
    return Scales(np.maximum(F, 1e-9), np.maximum(speed, 1e-9), np.maximum(span, 1e-9), np.maximum(af, 1e-9), trajs[0].dt,
                  int(system.spec["action_delay"].high), np.maximum(I, 1e-9), touching >= TOUCH_SHARE * len(keep))


def library(system, sc: Scales, effects=EFFECTS) -> list[Candidate]:
    """Every candidate for this model (``effects`` limits the kinds): per joint, per moving body,
    global, per actuator, each kind's hypotheses from its plug-in (``physics/kinds/``)."""
    unknown = set(effects) - set(ALL_EFFECTS)
    if unknown:
        raise ValueError(f"unknown effect(s) {sorted(unknown)}; the library has {', '.join(ALL_EFFECTS)}")
    m = system.mj
    out: list[Candidate] = []

    def add(effect, target, params, grid, scales, search, off=0.0):
        out.append(Candidate(effect, target, tuple(params), tuple(tuple(float(x) for x in g) for g in grid),
                             tuple(float(s) for s in scales), tuple(tuple(map(float, r)) for r in search), float(off)))

    targets = {kinds.JOINT: sorted(system.one_dof + system.balls), kinds.BODY: range(m.nbody), "": (-1,),
               kinds.ACTUATOR: range(m.nu)}
    for group in _GROUPS:
        plugins = [k for k in kinds.offering(group) if k.effect in effects]
        for t in targets[group]:
            for k in plugins:
                if group != kinds.JOINT or t not in system.balls or k.effect in BALL_EFFECTS:
                    k.candidates(system, sc, add, t)
    return out


def label(effect: str, target: str) -> str:
    return effect if not target else f"{effect}@{target}"
