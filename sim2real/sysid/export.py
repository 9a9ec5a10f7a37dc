"""Write the fitted model as MJCF (MjSpec), ready to drop into a simulator.

What MuJoCo can express natively is written natively, each kind by its plug-in's ``export``
(``physics/kinds/``): masses (inertia scaled with them), joint damping and springs, quadratic drag
(damping's second coefficient), actuator gains, force limits (saturation), a first-order actuator
filter (motor lag), a payload body at the payload site, symmetric Coulomb friction as ``frictionloss``.
Every fitted parameter, including those MuJoCo has no attribute for (friction asymmetry, delay,
backlash, sensor offset), is also stored as ``<custom><numeric name="sim2real:<param>">``.
"""
from __future__ import annotations

import os

import mujoco
import numpy as np

from sim2real.physics import kinds


class _Context:
    """What an export hook needs: the ``MjSpec`` being written, the ``System``, every fitted value by name."""

    def __init__(self, spec, system, values):
        self.spec, self.system, self.values = spec, system, values


def write_fitted_mjcf(xml_path: str, system, z: np.ndarray, fitted: dict[str, float], path: str) -> None:
    spec = mujoco.MjSpec.from_file(xml_path)
    sp = system.spec
    ctx = _Context(spec, system, dict(zip(sp.names, np.asarray(z, float))))
    for p in sp.params:
        k = kinds.owner(p.kind)
        if k is not None:
            k.export(ctx, p, ctx.values[p.name])
    for name, v in fitted.items():
        spec.add_numeric(name=f"sim2real:{name}", data=[float(v)])
    spec.compile()
    xml = spec.to_xml()
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(xml)
    os.replace(tmp, path)
