"""Contact friction: the sliding coefficient of a geom, or (index -1) of every robot geom that
touches (the envs' randomisable ``friction``); and the diagnosis' ``contact_friction``: the sliding
coefficient of every contact one body makes.

MuJoCo gives a contact the larger of its two geoms' frictions, so lowering a box's own friction
changes nothing while the floor keeps MuJoCo's default 1. ``contact_friction:<body>`` therefore
raises the body's geoms above every other geom's ``priority`` (a contact then takes the
higher-priority geom's friction, solref and solimp) and gives them the friction the contacts
already had: neutral exactly where the body's contacts mix to one friction from geoms with equal
priority, solref, solimp, solmix and condim (``body_params`` offers the parameter only there).
Two such bodies touching each other share the raised priority, so their contact mixes again (the
larger of their two values). Contacts made by a ``<pair>`` carry their own friction and are not
changed. The diagnosis offers
it for a body in contact in the recordings (``candidates.Scales.touch``), when asked for.
"""
from __future__ import annotations

import copy

import mujoco
import numpy as np

from sim2real.physics.kinds.base import BODY, Kind, name_of
from sim2real.physics.params import Param


class ContactFriction(Kind):
    owns = ("geom_friction",)
    order = 40

    def setup(self, pm) -> None:
        m = pm.mj
        # robot geoms that collide with something (a friction index of -1 means all of them)
        pm.touching_geoms = np.array([g for g in range(m.ngeom) if m.geom_bodyid[g] > 0 and m.geom_contype[g] > 0],
                                     np.int32)

    def apply(self, pm, z, get, f) -> None:
        for i, p in pm.spec.of_kind("geom_friction"):
            geoms = pm.touching_geoms if p.index < 0 else p.index
            f["geom_friction"] = get("geom_friction").at[geoms, 0].set(z[i])


def partners(m: mujoco.MjModel, g: int) -> np.ndarray:
    """Geoms another body holds that geom ``g`` can touch (``contype`` of one against
    ``conaffinity`` of the other, either way: MuJoCo's rule; parent-child filtering aside)."""
    other = m.geom_bodyid != m.geom_bodyid[g]
    match = ((m.geom_contype[g] & m.geom_conaffinity) | (m.geom_contype & m.geom_conaffinity[g])) != 0
    return np.flatnonzero(other & match)


def mixed_friction(m: mujoco.MjModel, b: int) -> np.ndarray | None:
    """``[3]``: the friction (sliding, torsional, rolling) every contact of body ``b`` gets, or None
    where the body touches nothing or its contacts do not mix to one value from geoms alike in
    everything a priority would change (then ``contact_friction:<body>`` could not be neutral)."""
    out = None
    for g in np.flatnonzero(m.geom_bodyid == b):
        for p in partners(m, g):
            same = (m.geom_priority[g] == m.geom_priority[p] and m.geom_condim[g] == m.geom_condim[p]
                    and m.geom_solmix[g] == m.geom_solmix[p] and np.array_equal(m.geom_solref[g], m.geom_solref[p])
                    and np.array_equal(m.geom_solimp[g], m.geom_solimp[p]))
            f = np.maximum(m.geom_friction[g], m.geom_friction[p])
            if not same or (out is not None and not np.array_equal(f, out)):
                return None
            out = f
    return out


def body_params(m: mujoco.MjModel, bodies) -> list[Param]:
    """``contact_friction:<body>`` for each body of ``bodies`` that can touch another body's geoms
    (``mixed_friction``): default the friction its contacts have, bounds 0 to 10."""
    ps = []
    for b in bodies:
        f = mixed_friction(m, b)
        if f is not None:
            ps.append(Param(f"contact_friction:{name_of(m, mujoco.mjtObj.mjOBJ_BODY, b)}", float(f[0]), 0.0, 10.0,
                            "-", "sliding friction of every contact the body's geoms make", "contact_friction", b))
    return ps


class BodyContactFriction(Kind):
    owns = ("contact_friction",)
    attach = BODY
    order = 41
    effect = "contact_friction"
    # asked for (``effects=[..., contact_friction]``): the default search's thresholds were tuned
    # on systems without contacts, and on the one contact probe it fits the friction (0.311 for
    # 0.3) without passing the test (``benchmarks/results/new_user_probes/README.md``)
    default_candidate = False

    def prepare(self, m, spec):
        ps = spec.of_kind("contact_friction")
        if not ps:
            return m
        mixed = {p.index: mixed_friction(m, p.index) for _, p in ps}  # (all before any geom changes)
        m = copy.copy(m)
        top = int(m.geom_priority.max()) + 1
        for b, f in mixed.items():
            for g in np.flatnonzero(m.geom_bodyid == b):
                m.geom_friction[g], m.geom_priority[g] = f, top
        return m

    def setup(self, pm) -> None:
        pm.contact_geoms = {p.index: np.flatnonzero(pm.mj.geom_bodyid == p.index).astype(np.int32)
                            for _, p in pm.spec.of_kind("contact_friction")}
        # the priority ``prepare`` gave them (the user's highest + 1), for the exported file
        pm.contact_priority = int(pm.mj.geom_priority.max())

    def apply(self, pm, z, get, f) -> None:
        for i, p in pm.spec.of_kind("contact_friction"):
            f["geom_friction"] = get("geom_friction").at[pm.contact_geoms[p.index], 0].set(z[i])

    def export(self, ctx, p, v) -> None:
        if v == p.default:
            return
        pm = ctx.system.physics
        top = pm.contact_priority
        f = pm.mj.geom_friction[pm.contact_geoms[p.index][0]]
        for g in ctx.spec.body(ctx.system.bodies[p.index]).geoms:
            g.friction = [float(v), float(f[1]), float(f[2])]
            g.priority = top
        ctx.native(p.name, f"the friction of the body's geoms, their priority raised to {top} so that "
                   "their contacts take it (MuJoCo otherwise takes the larger of two geoms' frictions)")

    def candidates(self, system, sc, add, target) -> None:
        bn = system.bodies[target]
        name = f"contact_friction:{bn}"
        if name not in system.spec or sc.touch is None or not sc.touch[target]:
            return
        mu = float(system.spec[name].default)
        c = mu if mu > 0.05 else 1.0
        add("contact_friction", bn, [name], [(f * c,) for f in (0.2, 0.5, 2.0)], [0.1 * c], [(0.0, 4.0 * c)],
            off=mu)
