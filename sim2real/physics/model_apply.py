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
from sim2real._mjx import mjx
from sim2real._precision import real

from sim2real.physics import kinds
from sim2real.physics.params import ParamSpec, clip


class PhysicsModel:
    """Static structure (compiled model, index arrays, spec) and the pure ``apply``.

    What each parameter kind changes is its plug-in's (``physics/kinds/``); this class runs them
    in their fixed order and recomputes what follows from all of them (subtree masses).

    Args:
      mj_model: compiled MuJoCo model (numpy), the nominal physics.
      spec: named parameters; a kind no plug-in owns is refused.
      joint_damping_dofs: dofs that the global ``joint_damping`` parameter sets.
    """

    def __init__(self, mj_model: mujoco.MjModel, spec: ParamSpec, joint_damping_dofs=()):
        self.spec = spec
        unknown = sorted({p.kind for p in spec.params if kinds.owner(p.kind) is None})
        if unknown:
            raise ValueError(f"parameter kind(s) {', '.join(repr(k) for k in unknown)}: no plug-in gives them a "
                             "meaning (sim2real/physics/kinds/)")
        self.kinds = [k for k in kinds.all_kinds() if any(spec.of_kind(kind) for kind in k.owns)]
        for k in self.kinds:
            mj_model = k.prepare(mj_model, spec)
        self.mj = mj_model
        self.mx = mjx.put_model(mj_model, device=jax.local_devices()[0])  # this process's (see plant.py)
        self.joint_damping_dofs = np.asarray(joint_damping_dofs, np.int32)
        for k in self.kinds:
            k.setup(self)
        # parent chain for subtree masses (static)
        self.parent = np.asarray(mj_model.body_parentid)

    # ------------------------------------------------------------------------------
    def apply(self, z: jnp.ndarray) -> mjx.Model:
        """Model fields for one physics vector ``z [P]`` (vmap for a batch)."""
        m0 = self.mx
        z = clip(self.spec, z)
        f = {}  # field name -> new array

        def get(name):
            return f[name] if name in f else getattr(m0, name)

        for k in self.kinds:
            k.apply(self, z, get, f)
        if "body_mass" in f:
            f["body_subtreemass"] = self._subtree_mass(f["body_mass"])
        return m0.replace(**f) if f else m0

    def _subtree_mass(self, body_mass: jnp.ndarray) -> jnp.ndarray:
        sub = body_mass
        for b in range(len(self.parent) - 1, 0, -1):  # children have larger ids than parents
            sub = sub.at[self.parent[b]].add(sub[b])
        return sub


# Fields ``apply`` may change, copied back for native MuJoCo (parity tests, exported MJCF).
APPLIED_FIELDS = (
    "body_mass", "body_ipos", "body_inertia", "body_iquat", "body_subtreemass", "geom_size", "geom_rbound",
    "geom_friction", "dof_damping", "dof_armature", "jnt_stiffness", "actuator_gainprm", "actuator_biasprm",
    "actuator_forcerange",
)


def to_mjmodel(pm: PhysicsModel, z) -> mujoco.MjModel:
    """A native ``MjModel`` with the fields ``pm.apply(z)`` computes (a copy; ``pm.mj`` is untouched)."""
    fields = _applied_fields(pm)(jnp.asarray(z, real()))
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
