"""Contact friction: the sliding coefficient of a geom, or (index -1) of every robot geom that touches."""
from __future__ import annotations

import numpy as np

from sim2real.physics.kinds.base import Kind


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
