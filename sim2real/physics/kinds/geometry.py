"""Geom sizes and body density: the mass properties follow (recomputed from the geoms, never stored)."""
from __future__ import annotations

from sim2real.physics import massprops
from sim2real.physics.kinds.base import Kind


class Geometry(Kind):
    """``geom_radius`` (a geom's first size) and ``density`` (every moving body's); a changed size
    changes the body's mass, centre of mass and inertia, computed from its geoms."""

    owns = ("geom_radius", "density")
    order = 10

    def setup(self, pm) -> None:
        m, spec = pm.mj, pm.spec
        size_geoms = {p.index for _, p in spec.of_kind("geom_radius")}
        if spec.of_kind("density"):
            pm.geom_bodies = sorted({int(m.geom_bodyid[g]) for g in range(m.ngeom) if m.geom_bodyid[g] > 0})
        else:
            pm.geom_bodies = sorted({int(m.geom_bodyid[g]) for g in size_geoms})
        pm.body_geoms = [massprops.describe_body(m, b) for b in pm.geom_bodies]
        dens = spec.of_kind("density")
        pm.density_row = dens[0][0] if dens else -1
        pm.default_density = float(dens[0][1].default) if dens else 1.0

    def apply(self, pm, z, get, f) -> None:
        spec, m0 = pm.spec, pm.mx
        geom_size = m0.geom_size
        rbound = m0.geom_rbound
        for i, p in spec.of_kind("geom_radius"):
            delta = z[i] - m0.geom_size[p.index, 0]
            geom_size = geom_size.at[p.index, 0].set(z[i])
            rbound = rbound.at[p.index].add(delta)
        if spec.of_kind("geom_radius"):
            f["geom_size"], f["geom_rbound"] = geom_size, rbound
        if pm.body_geoms:
            dens = z[pm.density_row] / pm.default_density if pm.density_row >= 0 else 1.0
            mass, ipos, inertia, iquat = m0.body_mass, m0.body_ipos, m0.body_inertia, m0.body_iquat
            for bg in pm.body_geoms:
                mb, cb, ib, qb = massprops.body_mass_properties(bg, geom_size, dens)
                mass, ipos, inertia = mass.at[bg.body].set(mb), ipos.at[bg.body].set(cb), inertia.at[bg.body].set(ib)
                if qb is not None:
                    iquat = iquat.at[bg.body].set(qb)
            f["body_mass"], f["body_ipos"], f["body_inertia"], f["body_iquat"] = mass, ipos, inertia, iquat
