"""``apply(z) -> mjx.Model``: one pure function from a physics vector to model fields.

Derived quantities are recomputed here, never stored: a changed size changes the body's mass,
centre of mass and inertia; a changed mass or payload changes the subtree masses.
Nothing here depends on ``z`` structurally, so ``vmap`` over envs with different physics is one
trace, and changing ``z`` (or the distribution it comes from) never recompiles.

Not recomputed (documented approximation, as Brax/Playground do): ``body_invweight0``,
``dof_invweight0``, ``actuator_acc0`` and ``stat.meaninertia``, which only scale constraint
softness and solver tolerances.
"""
from __future__ import annotations

import copy

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from mujoco import mjx

from sim2real.physics import massprops
from sim2real.physics.catalog import gain_law_entries, link_axis
from sim2real.physics.params import ParamSpec, clip

_NO_LIMIT = 1e30  # force clamp that never binds: exactly neutral


class PhysicsModel:
    """Static structure (compiled model, index arrays, spec) and the pure ``apply``.

    Args:
      mj_model: compiled MuJoCo model (numpy), the nominal physics.
      spec: named parameters; kinds understood here are listed in ``_MODEL_KINDS``.
      joint_damping_dofs: dofs that the global ``joint_damping`` parameter sets.
    """

    def __init__(self, mj_model: mujoco.MjModel, spec: ParamSpec, joint_damping_dofs=()):
        self.spec = spec
        if spec.of_kind("saturation"):
            # MJX fixes at put_model time which actuators clamp their force; give every actuator
            # the clamp with a range no force reaches, so per-env saturation is a traced value.
            mj_model = copy.copy(mj_model)
            free = mj_model.actuator_forcelimited == 0
            mj_model.actuator_forcerange[free] = [-_NO_LIMIT, _NO_LIMIT]
            mj_model.actuator_forcelimited[:] = 1
        self.mj = mj_model
        self.mx = mjx.put_model(mj_model)
        self.joint_damping_dofs = np.asarray(joint_damping_dofs, np.int32)
        m = mj_model
        size_geoms = {p.index for _, p in spec.of_kind("geom_radius")}
        if spec.of_kind("density"):
            self.geom_bodies = sorted({int(m.geom_bodyid[g]) for g in range(m.ngeom) if m.geom_bodyid[g] > 0})
        else:
            self.geom_bodies = sorted({int(m.geom_bodyid[g]) for g in size_geoms})
        self.body_geoms = [massprops.describe_body(m, b) for b in self.geom_bodies]
        self.default_density = (float(spec["density"].default) if "density" in spec else 1.0)
        # robot geoms that collide with something (a friction index of -1 means all of them)
        self.touching_geoms = np.array([g for g in range(m.ngeom) if m.geom_bodyid[g] > 0 and m.geom_contype[g] > 0],
                                       np.int32)
        # where each body's payload sits: a site named payload_<body>, else the centre of mass
        self.payload_pos = {}
        for _, p in spec.of_kind("payload"):
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, p.index)
            sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, f"payload_{name}")
            if sid >= 0:
                if m.site_bodyid[sid] != p.index:
                    raise ValueError(f"site 'payload_{name}' must belong to body '{name}'")
                self.payload_pos[p.index] = np.asarray(m.site_pos[sid], np.float32)
        # a payload_r parameter places the payload along the link instead (anchor + r * direction)
        self.payload_axis = {}
        for _, p in spec.of_kind("payload_r"):
            anchor, direction, _ = link_axis(m, p.index)
            self.payload_axis[p.index] = (np.asarray(anchor, np.float32), np.asarray(direction, np.float32))
        # parent chain for subtree masses (static)
        self.parent = np.asarray(m.body_parentid)

    # ------------------------------------------------------------------------------
    def apply(self, z: jnp.ndarray) -> mjx.Model:
        """Model fields for one physics vector ``z [P]`` (vmap for a batch)."""
        spec, m0 = self.spec, self.mx
        z = clip(spec, z)
        f = {}  # field name -> new array

        def get(name):
            return f[name] if name in f else getattr(m0, name)

        # --- geometry, density -> mass properties --------------------------------------
        geom_size = m0.geom_size
        rbound = m0.geom_rbound
        for i, p in spec.of_kind("geom_radius"):
            delta = z[i] - m0.geom_size[p.index, 0]
            geom_size = geom_size.at[p.index, 0].set(z[i])
            rbound = rbound.at[p.index].add(delta)
        if spec.of_kind("geom_radius"):
            f["geom_size"], f["geom_rbound"] = geom_size, rbound
        if self.body_geoms:
            dens = z[spec.index("density")] / self.default_density if "density" in spec else 1.0
            mass, ipos, inertia, iquat = m0.body_mass, m0.body_ipos, m0.body_inertia, m0.body_iquat
            for bg in self.body_geoms:
                mb, cb, ib, qb = massprops.body_mass_properties(bg, geom_size, dens)
                mass, ipos, inertia = mass.at[bg.body].set(mb), ipos.at[bg.body].set(cb), inertia.at[bg.body].set(ib)
                if qb is not None:
                    iquat = iquat.at[bg.body].set(qb)
            f["body_mass"], f["body_ipos"], f["body_inertia"], f["body_iquat"] = mass, ipos, inertia, iquat
        for i, p in spec.of_kind("body_mass"):
            scale = z[i] / p.default
            f["body_mass"] = get("body_mass").at[p.index].multiply(scale)
            f["body_inertia"] = get("body_inertia").at[p.index].multiply(scale)
        where = {p.index: z[i] for i, p in spec.of_kind("payload_r")}
        for i, p in spec.of_kind("payload"):
            f.update(self._add_payload(get, p.index, z[i], where.get(p.index)))
        if "body_mass" in f:
            f["body_subtreemass"] = self._subtree_mass(f["body_mass"])

        # --- contact friction -----------------------------------------------------------
        for i, p in spec.of_kind("geom_friction"):
            geoms = self.touching_geoms if p.index < 0 else p.index
            f["geom_friction"] = get("geom_friction").at[geoms, 0].set(z[i])

        # --- joint damping / springs -----------------------------------------------------
        if "joint_damping" in spec and len(self.joint_damping_dofs):
            f["dof_damping"] = get("dof_damping").at[self.joint_damping_dofs].set(z[spec.index("joint_damping")])
        if "damping_scale" in spec and len(self.joint_damping_dofs):
            f["dof_damping"] = get("dof_damping").at[self.joint_damping_dofs].multiply(z[spec.index("damping_scale")])
        for i, p in spec.of_kind("dof_damping"):
            f["dof_damping"] = get("dof_damping").at[self.mj.jnt_dofadr[p.index]].set(z[i])
        for i, p in spec.of_kind("viscous"):
            f["dof_damping"] = get("dof_damping").at[self.mj.jnt_dofadr[p.index]].add(z[i])
        for i, p in spec.of_kind("stiffness"):
            f["jnt_stiffness"] = get("jnt_stiffness").at[p.index].add(z[i])

        # --- actuators --------------------------------------------------------------------
        for kind in ("actuator_gain", "actuator_kv"):
            for i, p in spec.of_kind(kind):
                a, ratio = p.index, z[i] / p.default if p.default else z[i]
                for field, col in gain_law_entries(self.mj, kind, a):
                    name = f"actuator_{field}"
                    f[name] = get(name).at[a, col].set(getattr(m0, name)[a, col] * ratio)
        for i, p in spec.of_kind("saturation"):
            a, s = p.index, z[i]
            on = s > 0
            f["actuator_forcerange"] = get("actuator_forcerange").at[a].set(
                jnp.where(on, jnp.stack([-s, s]), m0.actuator_forcerange[a]))

        model = m0.replace(**f) if f else m0
        if "gravity" in spec:
            g = z[spec.index("gravity")]
            model = model.replace(opt=model.opt.replace(gravity=jnp.array([0.0, 0.0, -1.0]) * g))
        return model

    def _add_payload(self, get, b: int, mp, r=None):
        """Point mass ``mp`` at distance ``r`` along the link (``payload_r``), else at the body's
        ``payload_<body>`` site (its centre of mass if none).

        Mass, centre of mass and inertia follow (parallel-axis theorem); the result is kept
        diagonal in the body's principal frame, exact for a payload on a principal axis through
        the centre of mass, as at the tip of a link.
        """
        m, c = get("body_mass")[b], get("body_ipos")[b]
        if r is not None:
            anchor, direction = self.payload_axis[b]
            p = jnp.asarray(anchor) + r * jnp.asarray(direction)
        else:
            p = jnp.asarray(self.payload_pos.get(b, c))
        rot = massprops.quat_to_mat(get("body_iquat")[b])
        i_body = rot @ jnp.diag(get("body_inertia")[b]) @ rot.T
        c_new = (m * c + mp * p) / (m + mp)

        def shift(mass, r):
            return mass * (jnp.dot(r, r) * jnp.eye(3) - jnp.outer(r, r))

        total = i_body + shift(m, c - c_new) + shift(mp, p - c_new)
        diag = jnp.diagonal(rot.T @ total @ rot)
        return {"body_mass": get("body_mass").at[b].add(mp), "body_ipos": get("body_ipos").at[b].set(c_new),
                "body_inertia": get("body_inertia").at[b].set(diag)}

    def _subtree_mass(self, body_mass: jnp.ndarray) -> jnp.ndarray:
        sub = body_mass
        for b in range(len(self.parent) - 1, 0, -1):  # children have larger ids than parents
            sub = sub.at[self.parent[b]].add(sub[b])
        return sub


# Fields ``apply`` may change, copied back for native MuJoCo (parity tests, exported MJCF).
APPLIED_FIELDS = (
    "body_mass", "body_ipos", "body_inertia", "body_iquat", "body_subtreemass", "geom_size", "geom_rbound",
    "geom_friction", "dof_damping", "jnt_stiffness", "actuator_gainprm", "actuator_biasprm",
    "actuator_forcerange",
)


def to_mjmodel(pm: PhysicsModel, z) -> mujoco.MjModel:
    """A native ``MjModel`` with the fields ``pm.apply(z)`` computes (a copy; ``pm.mj`` is untouched)."""
    fields = _applied_fields(pm)(jnp.asarray(z, jnp.float32))
    m = copy.copy(pm.mj)
    for name in APPLIED_FIELDS:
        getattr(m, name)[:] = np.asarray(fields[name])
    m.opt.gravity[:] = np.asarray(fields["gravity"])
    # MuJoCo's C engine reads some derived constants (dof_M0 for "simple" bodies) that MJX
    # recomputes; refresh them so the native model really has the new masses, but keep the
    # constants apply() keeps at their defaults, so both engines see the same model.
    kept = {k: np.copy(getattr(m, k)) for k in _KEPT_CONSTANTS}
    meaninertia = float(m.stat.meaninertia)
    mujoco.mj_setConst(m, mujoco.MjData(m))
    for k, v in kept.items():
        getattr(m, k)[:] = v
    m.stat.meaninertia = meaninertia
    return m


def _applied_fields(pm: PhysicsModel):
    """``jit(z -> the APPLIED_FIELDS and gravity of pm.apply(z))``, built once per ``pm``: the
    diagnosis builds a native model for every residual it evaluates (hundreds), and run eagerly
    ``apply`` dispatches (and first compiles) each of its small ops one by one."""
    f = pm.__dict__.get("_applied_fields_jit")
    if f is None:
        def fields(z):
            mx = pm.apply(z)
            return {**{name: getattr(mx, name) for name in APPLIED_FIELDS}, "gravity": mx.opt.gravity}
        f = pm.__dict__["_applied_fields_jit"] = jax.jit(fields)
    return f


_KEPT_CONSTANTS = ("body_invweight0", "dof_invweight0", "tendon_invweight0", "actuator_acc0")
