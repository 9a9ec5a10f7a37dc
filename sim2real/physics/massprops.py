"""Mass properties of primitive geoms, so a changed size changes mass and inertia with it.

MuJoCo derives body mass and inertia from geoms at compile time (``inertiafromgeom``); MJX never
recompiles. :func:`body_mass_properties` redoes that derivation in JAX for the bodies whose
geoms a parameter resizes or re-densifies, with MuJoCo's own formulas (checked against
``MjSpec`` recompilation in ``tests/test_massprops.py``).

For a single-geom body the principal frame cannot turn, so the default ``body_iquat`` is kept
(no eigen-decomposition: its gradient is undefined for the repeated eigenvalues of symmetric
geoms). For several geoms the tensor is diagonalised again and ``body_iquat`` updated.
"""
from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import mujoco
import numpy as np

_SPHERE, _CAPSULE, _ELLIPSOID, _CYLINDER, _BOX = (
    int(mujoco.mjtGeom.mjGEOM_SPHERE),
    int(mujoco.mjtGeom.mjGEOM_CAPSULE),
    int(mujoco.mjtGeom.mjGEOM_ELLIPSOID),
    int(mujoco.mjtGeom.mjGEOM_CYLINDER),
    int(mujoco.mjtGeom.mjGEOM_BOX),
)
SUPPORTED = (_SPHERE, _CAPSULE, _ELLIPSOID, _CYLINDER, _BOX)


def geom_volume_inertia(gtype: int, size: jnp.ndarray):
    """Volume and unit-density principal inertia of one primitive geom.

    Args:
      gtype: static ``mjtGeom`` value.
      size: ``[3]`` MuJoCo geom size.
    Returns:
      ``(volume [], inertia [3])`` in the geom frame, for density 1.
    """
    if gtype == _SPHERE:
        r = size[0]
        v = 4.0 / 3.0 * jnp.pi * r**3
        i = 2.0 / 5.0 * v * r**2
        return v, jnp.stack([i, i, i])
    if gtype == _CAPSULE:
        r, h = size[0], 2.0 * size[1]  # h: cylinder height
        v_cyl = jnp.pi * r**2 * h
        v_sph = 4.0 / 3.0 * jnp.pi * r**3
        # cylinder part, then two hemispheres shifted along the axis (MuJoCo's formula)
        ixy = v_cyl * (3 * r**2 + h**2) / 12 + 2 * v_sph * r**2 / 5 + v_sph * h * (3 * r + 2 * h) / 8
        iz = v_cyl * r**2 / 2 + 2 * v_sph * r**2 / 5
        return v_cyl + v_sph, jnp.stack([ixy, ixy, iz])
    if gtype == _CYLINDER:
        r, h = size[0], 2.0 * size[1]
        v = jnp.pi * r**2 * h
        ixy = v * (3 * r**2 + h**2) / 12
        return v, jnp.stack([ixy, ixy, v * r**2 / 2])
    if gtype == _ELLIPSOID:
        a, b, c = size[0], size[1], size[2]
        v = 4.0 / 3.0 * jnp.pi * a * b * c
        return v, jnp.stack([v * (b**2 + c**2) / 5, v * (a**2 + c**2) / 5, v * (a**2 + b**2) / 5])
    if gtype == _BOX:
        a, b, c = 2 * size[0], 2 * size[1], 2 * size[2]
        v = a * b * c
        return v, jnp.stack([v * (b**2 + c**2) / 12, v * (a**2 + c**2) / 12, v * (a**2 + b**2) / 12])
    raise ValueError(f"geom type {gtype} has no analytic mass properties; use a primitive")


def _quat_to_mat(q: np.ndarray) -> np.ndarray:
    m = np.zeros(9)
    mujoco.mju_quat2Mat(m, np.asarray(q, np.float64))
    return m.reshape(3, 3)


@dataclasses.dataclass(frozen=True)
class BodyGeoms:
    """Static description of one body's geoms (numpy, built once per env)."""

    body: int
    geoms: tuple[int, ...]
    types: tuple[int, ...]
    rot: np.ndarray       # [G, 3, 3] geom frame -> body frame
    pos: np.ndarray       # [G, 3]   geom position in the body frame
    irot: np.ndarray      # [3, 3]   default principal (inertial) frame -> body frame
    density: float        # kg/m^3 implied by the compiled mass (uniform within the body)


def describe_body(m: mujoco.MjModel, body: int) -> BodyGeoms:
    geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] == body]
    types = tuple(int(m.geom_type[g]) for g in geoms)
    for g, t in zip(geoms, types):
        if t not in SUPPORTED:
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)
            raise ValueError(f"geom '{name}' (type {t}) has no analytic mass properties")
    vol = sum(float(geom_volume_inertia(t, np.asarray(m.geom_size[g]))[0]) for g, t in zip(geoms, types))
    return BodyGeoms(
        body=body,
        geoms=tuple(geoms),
        types=types,
        rot=np.stack([_quat_to_mat(m.geom_quat[g]) for g in geoms]),
        pos=np.stack([np.asarray(m.geom_pos[g]) for g in geoms]),
        irot=_quat_to_mat(m.body_iquat[body]),
        density=float(m.body_mass[body]) / vol,
    )


def body_mass_properties(bg: BodyGeoms, geom_size: jnp.ndarray, density_scale):
    """Mass, centre of mass and principal inertia of a body from its geoms.

    Args:
      bg: static body description.
      geom_size: ``[ngeom, 3]`` sizes of all geoms in the model (possibly changed).
      density_scale: scalar multiplier on the body's compiled density.
    Returns:
      ``(mass [], ipos [3], inertia [3], iquat [4] or None)``; ``None``: the default frame holds.
    """
    rho = bg.density * density_scale
    masses, inertias = [], []
    for g, t in zip(bg.geoms, bg.types):
        v, i = geom_volume_inertia(t, geom_size[g])
        masses.append(rho * v)
        inertias.append(rho * i)
    mass = jnp.stack(masses)                       # [G]
    com = (mass[:, None] * bg.pos).sum(0) / mass.sum()
    total = jnp.zeros((3, 3))
    for k in range(len(bg.geoms)):
        r = bg.rot[k]
        d = bg.pos[k] - com
        total = total + r @ jnp.diag(inertias[k]) @ r.T
        total = total + mass[k] * (jnp.dot(d, d) * jnp.eye(3) - jnp.outer(d, d))
    local = bg.irot.T @ total @ bg.irot  # tensor in the default principal frame
    if len(bg.geoms) == 1:
        return mass.sum(), com, jnp.diagonal(local), None
    evals, evecs = jnp.linalg.eigh(local)
    evecs = evecs.at[:, 2].multiply(jnp.sign(jnp.linalg.det(evecs)))  # proper rotation
    return mass.sum(), com, evals, mat_to_quat(bg.irot @ evecs)


def quat_to_mat(q: jnp.ndarray) -> jnp.ndarray:
    """Rotation matrix ``[3, 3]`` of a unit quaternion ``[4]`` (w, x, y, z)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    return jnp.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def mat_to_quat(r: jnp.ndarray) -> jnp.ndarray:
    """Unit quaternion ``[4]`` (w, x, y, z) of a rotation matrix ``[3, 3]`` (Shepperd's method)."""
    t = jnp.trace(r)
    cands = jnp.stack([
        jnp.stack([1 + t, r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]]),
        jnp.stack([r[2, 1] - r[1, 2], 1 + r[0, 0] - r[1, 1] - r[2, 2], r[0, 1] + r[1, 0], r[0, 2] + r[2, 0]]),
        jnp.stack([r[0, 2] - r[2, 0], r[0, 1] + r[1, 0], 1 - r[0, 0] + r[1, 1] - r[2, 2], r[1, 2] + r[2, 1]]),
        jnp.stack([r[1, 0] - r[0, 1], r[0, 2] + r[2, 0], r[1, 2] + r[2, 1], 1 - r[0, 0] - r[1, 1] + r[2, 2]]),
    ])
    q = cands[jnp.argmax(jnp.diagonal(cands))]  # the candidate with the largest pivot is stable
    return q / jnp.linalg.norm(q)
