"""Write the fitted model as MJCF (MjSpec), ready to drop into a simulator.

What MuJoCo can express natively is written natively, each kind by its plug-in's ``export``
(``physics/kinds/``): masses (inertia scaled with them), joint damping and springs, quadratic drag
(damping's second coefficient), actuator gains, force limits (saturation), a first-order actuator
filter (motor lag), the actuators' delay line (action delay), a payload body, symmetric Coulomb
friction as ``frictionloss`` and its asymmetry as a constant force (a bias-only actuator).
Every fitted parameter is also stored as ``<custom><numeric name="sim2real:<param>">``, and a
comment at the top of the file says which fitted effects MuJoCo could not simulate (backlash, a
sensor offset, a Stribeck term, ...): those live only in the ``<numeric>`` entries.
"""
from __future__ import annotations

import os

import mujoco
import numpy as np

from sim2real.physics import kinds


class _Context:
    """What an export hook needs: the ``MjSpec`` being written, the ``System``, every fitted value
    by name; and where a hook says how it wrote a value (``native``) or that it could not
    (``only_numeric``), for the file's comment."""

    def __init__(self, spec, system, values):
        self.spec, self.system, self.values = spec, system, values
        self.written: dict[str, str] = {}
        self.not_written: dict[str, str] = {}

    def native(self, name: str, how: str) -> None:
        self.written[name] = how

    def only_numeric(self, name: str, why: str) -> None:
        self.not_written[name] = why


def write_fitted_mjcf(xml_path: str, system, z: np.ndarray, fitted: dict[str, float], path: str) -> None:
    spec = mujoco.MjSpec.from_file(xml_path)
    _asset_dirs_from(spec, os.path.dirname(os.path.abspath(xml_path)), os.path.dirname(os.path.abspath(path)))
    sp = system.spec
    ctx = _Context(spec, system, dict(zip(sp.names, np.asarray(z, float))))
    for p in sp.params:
        k = kinds.owner(p.kind)
        if k is not None:
            k.export(ctx, p, ctx.values[p.name])
            # an effect parameter away from its neutral value whose kind writes nothing
            if (type(k).export is kinds.Kind.export and p.name in fitted and p.name not in ctx.written
                    and float(fitted[p.name]) != float(p.default)):
                ctx.only_numeric(p.name, "MuJoCo has no attribute for it")
    for name, v in fitted.items():
        spec.add_numeric(name=f"sim2real:{name}", data=[float(v)])
    spec.compile()
    xml = _with_comment(spec.to_xml(), ctx, fitted)
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(xml)
    os.replace(tmp, path)


def _asset_dirs_from(spec, model_dir: str, out_dir: str) -> None:
    """Point the spec's mesh and texture folders, relative in the user's file to ``model_dir``, at
    the same folders relative to ``out_dir``, where the fitted file is written: a fitted model of a
    robot with meshes (``meshdir="assets"``) did not load from the diagnosis folder. Relative, so
    the fitted file and the model's folder may move together; absolute folders are kept."""
    def read_from_files(*groups):
        return any(getattr(e, "file", "") for group in groups for e in group)

    for attr, used in (("meshdir", read_from_files(spec.meshes, spec.hfields, spec.skins)),
                       ("texturedir", read_from_files(spec.textures))):
        d = getattr(spec, attr)
        if used and not os.path.isabs(d):
            setattr(spec, attr, os.path.relpath(os.path.join(model_dir, d), out_dir))
    spec.modelfiledir = out_dir + os.sep  # (the compile before writing resolves them from there)


def _with_comment(xml: str, ctx: _Context, fitted: dict[str, float]) -> str:
    """``xml`` with a comment after its first line: what was written in MuJoCo's terms beyond
    plain attributes, and which fitted values MuJoCo cannot simulate (kept as ``<numeric>`` only)."""
    lines = ["Fitted by sim2real's diagnosis: every fitted value is also a <numeric name=\"sim2real:...\">."]
    for name, how in ctx.written.items():
        lines.append(f"  {name} = {fitted.get(name, ctx.values.get(name)):.6g}: written as {how}.")
    if ctx.not_written:
        lines.append("NOT simulated by this file (MuJoCo cannot express them; <numeric> only):")
        for name, why in ctx.not_written.items():
            lines.append(f"  {name} = {fitted.get(name, ctx.values.get(name)):.6g}: {why}.")
    body = "\n".join("     " + ln for ln in lines).replace("--", "- -")
    head, _, rest = xml.partition("\n")
    if not head.startswith("<mujoco"):
        return f"<!--\n{body}\n-->\n" + xml
    return f"{head}\n<!--\n{body}\n-->\n{rest}"
