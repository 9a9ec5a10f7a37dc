"""What a parameter *kind* is: one plug-in per kind, saying what it means in every place it acts.

A :class:`Kind` owns one or more ``Param.kind`` strings (a Coulomb plug-in owns ``coulomb`` and its
asymmetry and Stribeck terms) and overrides the hooks that apply to it; the rest do nothing.

==================  ============================================================================
hook                who calls it
==================  ============================================================================
``declares``        ``catalog.effect_params``: an effect parameter on every joint / actuator /
                    body (``attach``), neutral by default
``prepare, setup``  ``PhysicsModel.__init__``: structural model changes before ``put_model``;
                    static index data
``apply``           ``PhysicsModel.apply``: the ``mjx.Model`` fields a value changes (in ``order``)
``damping``         ``Effects.velocity_damping``: a velocity-dependent force written as damping
                    (implicit in MuJoCo's integrator, so stiff laws stay stable)
``export``          ``sysid.export``: the fitted value written into the user's ``MjSpec``
``candidates``      ``sysid.candidates.library``: the hypotheses the diagnosis searches
==================  ============================================================================

The command path (delay line, motor lag, backlash) keeps its state in ``EffectState`` and runs in
one fixed pipeline (``effects.Effects.actuate``): its kinds declare, export and offer candidates
here, but their dynamics stay together, where their order is visible.
"""
from __future__ import annotations

import jax.numpy as jnp
import mujoco
import numpy as np

JOINT, ACTUATOR, BODY = "joint", "actuator", "body"


class Kind:
    """One plug-in (subclass it in its own module under ``physics/kinds/``; it is found on import).

    Attributes:
      owns: the ``Param.kind`` strings this plug-in gives meaning to.
      attach: ``"joint"``, ``"actuator"`` or ``"body"`` when ``declares`` names an effect parameter
        declared on every such object (``catalog.effect_params``); ``""`` otherwise.
      declares: ``kind -> (default, low, high, unit, doc)`` of those effect parameters; a unit
        ``"N|Nm"`` reads the first for slide joints, the second for hinges.
      order: place in ``apply`` and, within its ``attach`` group, in the parameter vector (fixed:
        a saved physics vector keeps its meaning).
      effect: the diagnosis' name for the hypothesis this kind offers (``""``: none).
      candidate_order: place of that hypothesis in the library (within its ``attach`` group).
      default_candidate: searched by default; ``False`` keeps it to users who ask for it
        (``effects=[...]``), so adding a kind does not change what the default diagnosis says.
    """

    owns: tuple[str, ...] = ()
    attach: str = ""
    declares: dict = {}
    order: float = 0.0
    effect: str = ""
    candidate_order: float | None = None
    default_candidate: bool = True

    # ---------------------------------------------------------------- model ------------
    def prepare(self, m: mujoco.MjModel, spec) -> mujoco.MjModel:
        """The compiled model with any structural change this kind needs (copy before changing)."""
        return m

    def setup(self, pm) -> None:
        """Static data on the ``PhysicsModel`` (index arrays), once."""

    def apply(self, pm, z, get, f: dict) -> None:
        """Write the ``mjx.Model`` fields that ``z`` changes into ``f`` (``get(name)``: current value)."""

    # ------------------------------------------------------------- dynamics ------------
    def damping_setup(self, m: mujoco.MjModel, spec, cfg):
        """``(dof indices [J], static data)`` for ``damping``, or None when this kind adds none."""
        return None

    def damping(self, data, z, qvel):
        """``[J]`` damping to add on its dofs for this physics sub-step (zero where off)."""
        raise NotImplementedError

    # ---------------------------------------------------------------- sysid ------------
    def export(self, ctx, p, v: float) -> None:
        """Write parameter ``p`` at its fitted value ``v`` into ``ctx.spec`` (an ``MjSpec``)."""

    def candidates(self, system, sc, add, target: int) -> None:
        """Offer hypotheses for object ``target`` (joint / actuator / body id; -1 for global)
        through ``add(effect, target_name, params, grid, scales, search)``."""


def name_of(m: mujoco.MjModel, obj, i: int) -> str:
    n = mujoco.mj_id2name(m, obj, i)
    if not n:
        raise ValueError(f"object {obj} #{i} has no name; name every joint/actuator/body/geom you randomise")
    return n


def unit_for(unit: str, slide: bool) -> str:
    """``"N|Nm"`` -> the slide (first) or hinge (last) unit."""
    return unit.split("|")[0 if slide else -1]


def coef(current, k: int = 0) -> float:
    """Coefficient ``k`` of a joint's damping/stiffness: MuJoCo >= 3.4 stores them as arrays
    (polynomial coefficients), older versions as floats."""
    return float(np.ravel(current)[k])


def set_coef(current, v: float, k: int = 0):
    """``current`` with polynomial coefficient ``k`` set to ``v``, in the type the spec expects."""
    if np.ndim(current):
        out = np.array(current, float).ravel().copy()
        out[k] = v
        return out
    if k:
        raise ValueError("this MuJoCo stores one damping coefficient; a polynomial term needs MuJoCo >= 3.4")
    return float(v)


def add_magnitude(add, effect: str, target: str, param: str, c: float, top: float) -> None:
    """A one-parameter hypothesis of typical size ``c``: screened at 3%, 10% and 30% of it, its
    scale 10%, searched over ``[0, top * c]``."""
    add(effect, target, [param], [(f * c,) for f in (0.03, 0.1, 0.3)], [0.1 * c], [(0.0, top * c)])


def rows(spec, kind: str, ids) -> np.ndarray:
    """Index into z of ``kind`` for each id in ``ids`` (or -1 where the spec has no such entry)."""
    by_id = {p.index: i for i, p in spec.of_kind(kind)}
    return np.array([by_id.get(int(k), -1) for k in ids], np.int32)


def take(z, rows_, default=0.0):
    """``z[rows]`` ``[len(rows)]``, ``default`` where a row is -1."""
    rows_ = np.asarray(rows_)
    if rows_.size == 0:
        return jnp.zeros((0,))
    return jnp.where(rows_ >= 0, z[np.maximum(rows_, 0)], default)
