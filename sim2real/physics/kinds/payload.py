"""A payload: a point mass on a body, at a ``payload_<body>`` site, its centre of mass, a fitted
distance along the link (``payload_r``, a hinged body), or a fitted place in the body's frame
(``payload_x/y/z``, a body that flies or turns about a point: a camera under a drone; or one
hinged through its centre of mass or welded to a moving body: a gripper on an arm's flange, a tool
in a hand); the diagnosis' ``mass_offset``."""
from __future__ import annotations

import jax.numpy as jnp
import mujoco
import numpy as np

from sim2real.physics import massprops
from sim2real.physics.kinds.base import BODY, TURNING, Kind, name_of
from sim2real.physics.params import Param

HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)


def link_axis(m: mujoco.MjModel, b: int) -> tuple[np.ndarray, np.ndarray, float] | None:
    """``(anchor, unit direction, length)`` of a body hinged to its parent: from the joint axis's
    point through the centre of mass (body frame); None when the body has no hinge or its centre
    of mass sits on the axis (a payload there is only a mass change)."""
    if m.body_jntnum[b] != 1 or m.jnt_type[m.body_jntadr[b]] != mujoco.mjtJoint.mjJNT_HINGE:
        return None
    j = m.body_jntadr[b]
    anchor = np.asarray(m.jnt_pos[j], float)
    axis = np.asarray(m.jnt_axis[j], float)
    r = np.asarray(m.body_ipos[b], float) - anchor
    r = r - axis * np.dot(r, axis)  # the part perpendicular to the axis is what a payload acts through
    length = float(np.linalg.norm(r))
    if length < 1e-4:
        return None
    return anchor, r / length, length


_AXES = ("payload_x", "payload_y", "payload_z")


def body_reach(m: mujoco.MjModel, b: int) -> float:
    """How far body ``b``'s geoms reach from its centre of mass (m): its size."""
    gs = [g for g in range(m.ngeom) if m.geom_bodyid[g] == b]
    return max([float(np.linalg.norm(m.geom_pos[g] - m.body_ipos[b]) + m.geom_rbound[g]) for g in gs] + [1e-3])


def position_params(m: mujoco.MjModel, bodies) -> list[Param]:
    """``payload_r:<body>``: distance of a payload from the joint axis along the link (through the
    centre of mass), for hinged bodies; the payload sits at the link's far end (twice the centre
    of mass distance, the tip of a uniform link) by default. ``payload_x/y/z:<body>``: its place
    in the body's frame relative to the centre of mass, for a body on a free or ball joint (a
    drone, a floating base, a spherical pendulum), on a hinge through its centre of mass (a
    wheel; an arm's last link, whose gripper sits out on the flange) or welded to a moving body
    (a hand on a flange), within twice the body's reach either way; at the centre of mass by
    default. ``bodies``: the moving ones."""
    ps = []
    for b in bodies:
        ax = link_axis(m, b)
        if ax is None:
            # (a hinged body whose centre of mass is on its axis -- a wheel, an arm's last link --
            # and a body welded to a moving one -- a hand on a flange -- are placed so too: what
            # they carry acts on every joint before them by where it is)
            if m.body_jntnum[b] == 0 or m.body_jntnum[b] == 1 and int(m.jnt_type[m.body_jntadr[b]]) in TURNING + (HINGE,):
                reach = round(2 * body_reach(m, b), 6)
                name = name_of(m, mujoco.mjtObj.mjOBJ_BODY, b)
                ps += [Param(f"{k}:{name}", 0.0, -reach, reach, "m", f"the payload's {k[-1]} from the centre of mass "
                             "(body frame)", k, b) for k in _AXES]
            continue
        length = ax[2]
        ps.append(Param(f"payload_r:{name_of(m, mujoco.mjtObj.mjOBJ_BODY, b)}", round(2 * length, 6), 0.0,
                        round(4 * length, 6), "m", "distance of the payload from the joint axis, along the link",
                        "payload_r", b))
    return ps


class Payload(Kind):
    owns = ("payload", "payload_r") + _AXES
    attach = BODY
    declares = {"payload": (0.0, 0.0, 1e3, "kg", "point mass at the body's payload_<body> site (else its centre of mass)")}
    order = 30
    effect = "mass_offset"

    def setup(self, pm) -> None:
        m = pm.mj
        # where each body's payload sits: a site named payload_<body>, else the centre of mass
        pm.payload_pos = {}
        for _, p in pm.spec.of_kind("payload"):
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, p.index)
            sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, f"payload_{name}")
            if sid >= 0:
                if m.site_bodyid[sid] != p.index:
                    raise ValueError(f"site 'payload_{name}' must belong to body '{name}'")
                pm.payload_pos[p.index] = np.asarray(m.site_pos[sid], np.float32)
        # a payload_r parameter places the payload along the link instead (anchor + r * direction)
        pm.payload_axis = {}
        for _, p in pm.spec.of_kind("payload_r"):
            anchor, direction, _ = link_axis(m, p.index)
            pm.payload_axis[p.index] = (np.asarray(anchor, np.float32), np.asarray(direction, np.float32))
        # a payload_x/y/z triple moves it in the body's frame from where it would sit
        offset = {}
        for k, axis in enumerate(_AXES):
            for i, p in pm.spec.of_kind(axis):
                offset.setdefault(p.index, [0, 0, 0])[k] = i
        pm.payload_offset = {b: np.array(idx) for b, idx in offset.items()}   # body -> [3] indices into z

    def apply(self, pm, z, get, f) -> None:
        where = {p.index: z[i] for i, p in pm.spec.of_kind("payload_r")}
        for i, p in pm.spec.of_kind("payload"):
            shift = pm.payload_offset.get(p.index)
            f.update(self._add(pm, get, p.index, z[i], where.get(p.index),
                               None if shift is None else z[shift]))

    @staticmethod
    def _add(pm, get, b: int, mp, r=None, shift=None):
        """Point mass ``mp`` at distance ``r`` along the link (``payload_r``), else at the body's
        ``payload_<body>`` site (its centre of mass if none), moved by ``shift`` ``[3]`` (m, body
        frame; ``payload_x/y/z``).

        Mass, centre of mass and inertia follow (parallel-axis theorem); the result is kept
        diagonal in the body's principal frame, exact for a payload on a principal axis through
        the centre of mass, as at the tip of a link.
        """
        m, c = get("body_mass")[b], get("body_ipos")[b]
        if r is not None:
            anchor, direction = pm.payload_axis[b]
            p = jnp.asarray(anchor) + r * jnp.asarray(direction)
        else:
            p = jnp.asarray(pm.payload_pos.get(b, c))
        if shift is not None:
            p = p + shift
        rot = massprops.quat_to_mat(get("body_iquat")[b])
        i_body = rot @ jnp.diag(get("body_inertia")[b]) @ rot.T
        c_new = (m * c + mp * p) / (m + mp)

        def shift(mass, r):
            return mass * (jnp.dot(r, r) * jnp.eye(3) - jnp.outer(r, r))

        total = i_body + shift(m, c - c_new) + shift(mp, p - c_new)
        diag = jnp.diagonal(rot.T @ total @ rot)
        return {"body_mass": get("body_mass").at[b].add(mp), "body_ipos": get("body_ipos").at[b].set(c_new),
                "body_inertia": get("body_inertia").at[b].set(diag)}

    def export(self, ctx, p, v) -> None:
        if p.kind != "payload" or v <= 0:
            return
        system = ctx.system
        bname = system.bodies[p.index]
        if p.index in system.physics.payload_axis:  # along the link, at the fitted distance
            anchor, direction = system.physics.payload_axis[p.index]
            pos = np.asarray(anchor) + ctx.values[f"payload_r:{bname}"] * np.asarray(direction)
        else:
            pos = system.physics.payload_pos.get(p.index, system.mj.body_ipos[p.index])
        if p.index in system.physics.payload_offset:
            pos = np.asarray(pos) + np.array([ctx.values[f"{k}:{bname}"] for k in _AXES])
        child = ctx.spec.body(bname).add_body(name=f"payload_mass_{bname}", pos=list(map(float, pos)))
        child.mass = v
        child.inertia = [1e-6 * v] * 3
        child.explicitinertial = True

    def candidates(self, system, sc, add, target) -> None:
        # a payload anywhere along a hinged link, or anywhere on a body that flies, turns about
        # a point or turns about an axis through its centre of mass (position_params)
        bn = system.bodies[target]
        mb = float(system.mj.body_mass[target])
        r_name = f"payload_r:{bn}"
        at = [f"{k}:{bn}" for k in _AXES]
        if at[0] in system.spec:
            m = system.mj
            if m.body_jntnum[target] == 0 or int(m.jnt_type[m.body_jntadr[target]]) == HINGE:
                # a body hinged through its centre of mass or welded to a moving one is a flange,
                # a hand or a wheel: what it carries is sized by the arm behind it, not by itself
                # (a UR5e's 0.19 kg flange under a 1 kg gripper): a tenth of the mass of the bodies
                # from the world to it (the fixed base's included) at least
                chain, b = 0.0, target
                while b > 0:
                    chain, b = chain + float(m.body_mass[b]), int(m.body_parentid[b])
                mb = max(mb, 0.1 * chain)
            # screened at its centre of mass and half its reach along each axis either way
            reach = system.spec[at[0]].high
            places = [np.zeros(3)] + [s * 0.25 * reach * e for e in np.eye(3) for s in (1, -1)]
            add("mass_offset", bn, [f"payload:{bn}", *at], [(f * mb, *x) for f in (0.15, 0.4) for x in places],
                [0.3 * mb] + [0.25 * reach] * 3, [(0.0, 5.0 * mb)] + [(-reach, reach)] * 3)
            return
        if r_name not in system.spec:
            return
        p = system.spec[r_name]
        L = p.default  # the link's far end
        add("mass_offset", bn, [f"payload:{bn}", r_name],
            [(f * mb, r * L) for f in (0.15, 0.4, 1.0) for r in (0.5, 1.0)], [0.3 * mb, 0.5 * L],
            [(0.0, 5.0 * mb), (0.0, float(p.high))])
