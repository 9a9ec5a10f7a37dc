"""Write the fitted model as MJCF (MjSpec), ready to drop into a simulator.

What MuJoCo can express natively is written natively: masses (inertia scaled with them), joint
damping and springs, actuator gains, force limits (saturation), a first-order actuator filter
(motor lag), a payload body at the payload site, symmetric Coulomb friction as ``frictionloss``.
Every fitted parameter, including those MuJoCo has no attribute for (friction asymmetry, delay,
backlash, sensor offset), is also stored as ``<custom><numeric name="sim2real:<param>">``.
"""
from __future__ import annotations

import os

import mujoco
import numpy as np

from sim2real.physics.catalog import gain_law_entries


def write_fitted_mjcf(xml_path: str, system, z: np.ndarray, fitted: dict[str, float], path: str) -> None:
    spec = mujoco.MjSpec.from_file(xml_path)
    sp = system.spec
    zd = dict(zip(sp.names, np.asarray(z, float)))
    for p in sp.params:
        v = zd[p.name]
        if p.kind == "body_mass" and v != p.default:
            # the compiled nominal's mass properties (MJCF often gives mass through geoms, with no
            # <inertial>), scaled, written as an explicit inertial
            b = spec.body(system.bodies[p.index])
            scale = v / p.default
            m = system.mj
            b.mass = v
            b.ipos = [float(x) for x in m.body_ipos[p.index]]
            b.iquat = [float(x) for x in m.body_iquat[p.index]]
            b.inertia = [float(x) * scale for x in m.body_inertia[p.index]]
            b.explicitinertial = True
        elif p.kind == "dof_damping":
            j = spec.joint(system.joints[p.index])
            j.damping = _set0(j.damping, v)
        elif p.kind == "viscous" and v > 0:
            j = spec.joint(system.joints[p.index])
            j.damping = _set0(j.damping, _first(j.damping) + v)
        elif p.kind == "stiffness" and v > 0:
            j = spec.joint(system.joints[p.index])
            j.stiffness = _set0(j.stiffness, _first(j.stiffness) + v)
        elif p.kind == "coulomb" and (v > 0 or p.default > 0):
            spec.joint(system.joints[p.index]).frictionloss = v
        elif p.kind in ("actuator_gain", "actuator_kv") and v != p.default and p.default:
            a = spec.actuator(system.actuators[p.index])
            for field, col in gain_law_entries(system.mj, p.kind, p.index):
                getattr(a, field)[col] = float(getattr(system.mj, f"actuator_{field}")[p.index, col]) * v / p.default
        elif p.kind == "saturation" and v > 0:
            a = spec.actuator(system.actuators[p.index])
            a.forcelimited = 1
            a.forcerange = [-v, v]
        elif p.kind == "motor_lag" and v > 0 and system.mj.actuator_dyntype[p.index] == 0:
            # (an actuator with dynamics of its own cannot take a second filter: <numeric> only)
            a = spec.actuator(system.actuators[p.index])
            a.dyntype = mujoco.mjtDyn.mjDYN_FILTEREXACT
            a.dynprm[0] = v
            a.actlimited = 0
        elif p.kind == "payload" and v > 0:
            bname = system.bodies[p.index]
            if p.index in system.physics.payload_axis:  # along the link, at the fitted distance
                anchor, direction = system.physics.payload_axis[p.index]
                pos = np.asarray(anchor) + zd[f"payload_r:{bname}"] * np.asarray(direction)
            else:
                pos = system.physics.payload_pos.get(p.index, system.mj.body_ipos[p.index])
            child = spec.body(bname).add_body(name=f"payload_mass_{bname}", pos=list(map(float, pos)))
            child.mass = v
            child.inertia = [1e-6 * v] * 3
            child.explicitinertial = True
    for name, v in fitted.items():
        spec.add_numeric(name=f"sim2real:{name}", data=[float(v)])
    spec.compile()
    xml = spec.to_xml()
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(xml)
    os.replace(tmp, path)


def _first(current) -> float:
    """MuJoCo >= 3.4 stores joint damping/stiffness as arrays (polynomial coefficients); older as floats."""
    return float(np.ravel(current)[0])


def _set0(current, v: float):
    """``current`` with its first (linear) coefficient set to ``v``, in the type the spec expects."""
    if np.ndim(current):
        out = np.array(current, float).ravel().copy()
        out[0] = v
        return out
    return float(v)
