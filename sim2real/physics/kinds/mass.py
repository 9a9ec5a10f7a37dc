"""Body mass: inertia scales with it (the body's shape is kept)."""
from __future__ import annotations

import mujoco

from sim2real.physics.kinds.base import Kind, name_of
from sim2real.physics.params import Param


def declare(m: mujoco.MjModel, bodies) -> list[Param]:
    """``mass:<body>`` for each body id, bounds 1e-3 to 1e3 times the nominal mass."""
    ps = []
    for b in bodies:
        mass = float(m.body_mass[b])
        ps.append(Param(f"mass:{name_of(m, mujoco.mjtObj.mjOBJ_BODY, b)}", round(mass, 6), 1e-3 * mass, 1e3 * mass,
                        "kg", "body mass (inertia scaled with it)", "body_mass", b))
    return ps


class BodyMass(Kind):
    owns = ("body_mass",)
    order = 20

    def apply(self, pm, z, get, f) -> None:
        for i, p in pm.spec.of_kind("body_mass"):
            scale = z[i] / p.default
            f["body_mass"] = get("body_mass").at[p.index].multiply(scale)
            f["body_inertia"] = get("body_inertia").at[p.index].multiply(scale)

    def export(self, ctx, p, v) -> None:
        if v == p.default:
            return
        # the compiled nominal's mass properties (MJCF often gives mass through geoms, with no
        # <inertial>), scaled, written as an explicit inertial
        b = ctx.spec.body(ctx.system.bodies[p.index])
        scale = v / p.default
        m = ctx.system.mj
        b.mass = v
        b.ipos = [float(x) for x in m.body_ipos[p.index]]
        b.iquat = [float(x) for x in m.body_iquat[p.index]]
        b.inertia = [float(x) * scale for x in m.body_inertia[p.index]]
        # the principal inertia above replaces a full tensor (a URDF's <inertia ixx.. iyz>): MuJoCo
        # refuses a body given both; NaN first is MjSpec's "not given"
        b.fullinertia = [float("nan")] + [0.0] * 5
        b.explicitinertial = True
