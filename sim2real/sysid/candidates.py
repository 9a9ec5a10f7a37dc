"""The candidate missing-physics effects the diagnosis searches, with their search grids.

Each candidate is an effect of the simulator's effects library attached to one joint, actuator
or body (or global), described by the physics parameters it sets. Every candidate is screened on
a small grid of its own magnitude (``grid``: simulated at each point, the nominal parameters
re-solved linearly), then the best are fitted by Gauss-Newton on the simulation error.

=====================  ==========  ==========================================================
effect                 attached    parameters (spec names)
=====================  ==========  ==========================================================
coulomb_friction       joint       ``coulomb`` (+ ``coulomb_asym``: a level per direction)
viscous_damping        joint       ``viscous`` (only where the MJCF declares no damping)
joint_stiffness        joint       ``stiffness`` (only where the MJCF declares no spring)
sensor_offset          joint       ``sensor_offset``
mass_offset            body        ``payload`` and ``payload_r`` (a point mass along the link)
action_delay           global      ``action_delay`` (samples, fractional)
motor_lag              actuator    ``motor_lag`` (time constant, s)
actuator_saturation    actuator    ``saturation`` (force limit, actuator force units)
backlash               actuator    ``backlash`` (dead band width, joint units)
=====================  ==========  ==========================================================

Grids are in the system's own scales (``Scales``): the force a joint needs, its speed and
range, the actuator's forces, the sample period. A search that ends at the edge of its range is
widened once (``widen``) before the diagnosis gives up on it.
"""
from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

EFFECTS = ("none", "coulomb_friction", "viscous_damping", "joint_stiffness", "sensor_offset", "mass_offset",
           "action_delay", "motor_lag", "actuator_saturation", "backlash")


@dataclasses.dataclass(frozen=True)
class Candidate:
    """One hypothesis: ``effect`` at ``target``.

    Attributes:
      params: spec parameters this effect sets (besides the nominal ones).
      grid: screening points, each a tuple of values for ``params``.
      scales: typical magnitude of each parameter (finite-difference steps, standard errors).
      search: range of each parameter the search covers (a fit ending at an edge says so).
    """

    effect: str
    target: str
    params: tuple
    grid: tuple
    scales: tuple
    search: tuple

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
            return v >= 0.98 * self.search[0][1]
        return abs(v) <= 1e-3 * self.scales[0]

    def widen(self) -> "Candidate":
        """The same candidate with its (first parameter's) range and grid pushed past the edge."""
        lo, hi = self.search[0]
        pts = [g[0] for g in self.grid]
        if self.effect == "actuator_saturation":  # a limit below the lowest grid point
            new = tuple((v,) + g[1:] for v, g in zip(np.geomspace(lo / 4, lo, 4), [self.grid[0]] * 4))
            return dataclasses.replace(self, grid=new, search=((lo / 4, hi),) + self.search[1:])
        top = max(pts)
        new = tuple((v,) + self.grid[0][1:] for v in np.geomspace(top * 1.5, top * 4, 3))
        return dataclasses.replace(self, grid=new, search=((lo, hi * 4),) + self.search[1:])


@dataclasses.dataclass
class Scales:
    """What sizes the grids: per joint the generalised force it needs (RMS of the nominal inverse
    dynamics), its RMS speed, range and inertia (the mass matrix's diagonal at the mean pose);
    per actuator the 99.5th percentile of its force; the sample period; the longest delay the
    buffer holds (samples)."""

    force: np.ndarray
    speed: np.ndarray
    range: np.ndarray
    act_force: np.ndarray
    dt: float
    max_delay: int
    inertia: np.ndarray = None


def scales_from(system, trajs, act_force: np.ndarray) -> Scales:
    """``act_force [N, nu]``: the nominal model's actuator forces along the data (predicted)."""
    m = system.mj
    d = mujoco.MjData(m)
    q = np.concatenate([t.q for t in trajs])
    v = np.concatenate([t.v for t in trajs])
    a = np.concatenate([t.a for t in trajs])
    keep = np.linspace(0, len(q) - 1, min(len(q), 3000)).astype(int)
    frc = np.empty((len(keep), m.nv))
    for i, k in enumerate(keep):
        d.qpos[:], d.qvel[:], d.qacc[:] = q[k], v[k], a[k]
        mujoco.mj_inverse(m, d)
        frc[i] = d.qfrc_inverse
    dof = lambda j: m.jnt_dofadr[j]  # noqa: E731
    F = np.array([np.sqrt(np.mean(frc[:, dof(j)] ** 2)) for j in range(m.njnt)])
    af = (np.percentile(np.abs(act_force), 99.5, axis=0) if act_force.size else np.zeros(m.nu))
    d.qpos[:] = q.mean(0)
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    I = np.array([M[m.jnt_dofadr[j], m.jnt_dofadr[j]] for j in range(m.njnt)])
    return Scales(np.maximum(F, 1e-9), np.maximum(np.sqrt(np.mean(v**2, 0)), 1e-9),
                  np.maximum(np.ptp(q, 0), 1e-9), np.maximum(af, 1e-9), trajs[0].dt,
                  int(system.spec["action_delay"].high), np.maximum(I, 1e-9))


def library(system, sc: Scales, effects=EFFECTS) -> list[Candidate]:
    """Every candidate for this model (``effects`` limits the kinds)."""
    unknown = set(effects) - set(EFFECTS)
    if unknown:
        raise ValueError(f"unknown effect(s) {sorted(unknown)}; the library has {', '.join(EFFECTS)}")
    m, spec = system.mj, system.spec
    out: list[Candidate] = []

    def add(effect, target, params, grid, scales, search):
        out.append(Candidate(effect, target, tuple(params), tuple(tuple(float(x) for x in g) for g in grid),
                             tuple(float(s) for s in scales), tuple(tuple(map(float, r)) for r in search)))

    for j, jn in enumerate(system.joints):
        F, V, R = sc.force[j], sc.speed[j], sc.range[j]
        slide = m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
        if "coulomb_friction" in effects and not system.declared_friction(jn):
            add("coulomb_friction", jn, [f"coulomb:{jn}"], [(f * F,) for f in (0.03, 0.1, 0.3)], [0.1 * F],
                [(0.0, 2.0 * F)])
        if "viscous_damping" in effects and not system.declared_damping(jn):
            c = F / V
            add("viscous_damping", jn, [f"viscous:{jn}"], [(f * c,) for f in (0.03, 0.1, 0.3)], [0.1 * c],
                [(0.0, 3.0 * c)])
        if "joint_stiffness" in effects and not system.declared_stiffness(jn):
            k = F / (0.5 * R)
            add("joint_stiffness", jn, [f"stiffness:{jn}"], [(f * k,) for f in (0.03, 0.1, 0.3)], [0.1 * k],
                [(0.0, 3.0 * k)])
        if "sensor_offset" in effects:
            o = 0.05 * R if slide else min(0.05, 0.05 * R)
            add("sensor_offset", jn, [f"sensor_offset:{jn}"], [(s * f * o,) for f in (0.4, 2.0) for s in (-1, 1)],
                [o], [(-30 * o, 30 * o)])
    if "mass_offset" in effects:
        for _, p in spec.of_kind("payload_r"):
            b = p.index
            bn = system.bodies[b]
            mb = float(m.body_mass[b])
            L = p.default  # the link's far end
            add("mass_offset", bn, [f"payload:{bn}", f"payload_r:{bn}"],
                [(f * mb, r * L) for f in (0.15, 0.4, 1.0) for r in (0.5, 1.0)], [0.3 * mb, 0.5 * L],
                [(0.0, 5.0 * mb), (0.0, float(p.high))])
    dt = sc.dt
    if "action_delay" in effects and m.nu:
        pts = [d for d in (0.4, 1.0, 2.0, 3.5, 6.0, 10.0, 17.0, 28.0, 45.0, 70.0) if d <= sc.max_delay - 1]
        add("action_delay", "", ["action_delay"], [(d,) for d in pts], [1.0], [(0.1, float(max(pts)))])
    for a, an in enumerate(system.actuators):
        j = int(m.actuator_trnid[a, 0])
        if "motor_lag" in effects:
            taus = np.geomspace(max(0.4 * dt, 0.002), 0.25, 7)
            add("motor_lag", an, [f"motor_lag:{an}"], [(t,) for t in taus], [float(taus[2])],
                [(0.25 * float(taus[0]), 0.25)])
        if "actuator_saturation" in effects:
            f = sc.act_force[a]
            add("actuator_saturation", an, [f"saturation:{an}"], [(q * f,) for q in (0.2, 0.32, 0.5, 0.75)],
                [0.2 * f], [(0.2 * f, 1.0 * f)])
        if "backlash" in effects:
            # the dead band's width and the inertia of the motor side that crosses it (a few
            # percent of the joint's own, unknown: fitted)
            slide = m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
            widths = np.geomspace(4e-5, 2e-3, 4) if slide else np.geomspace(0.004, 0.06, 4)
            J = float(sc.inertia[j]) if sc.inertia is not None else 1e-2
            add("backlash", an, [f"backlash:{an}", f"backlash_inertia:{an}"],
                [(w, f * J) for w in widths for f in (0.01, 0.1)], [float(widths[1]), 0.03 * J],
                [(0.25 * float(widths[0]), float(widths[-1])), (1e-4 * J, 2.0 * J)])
    return out


def label(effect: str, target: str) -> str:
    return effect if not target else f"{effect}@{target}"
