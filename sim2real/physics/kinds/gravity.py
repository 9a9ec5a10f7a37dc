"""Gravity magnitude along -z."""
from __future__ import annotations

import jax.numpy as jnp

from sim2real.physics.kinds.base import Kind


class Gravity(Kind):
    owns = ("gravity",)
    order = 90

    def apply(self, pm, z, get, f) -> None:
        for i, _ in pm.spec.of_kind("gravity"):
            m0 = pm.mx
            f["opt"] = m0.opt.replace(gravity=jnp.array([0.0, 0.0, -1.0]) * z[i])
