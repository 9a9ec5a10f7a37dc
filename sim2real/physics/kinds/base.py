"""What a parameter *kind* is: one plug-in per kind, saying what it means in every place it acts.

A :class:`Kind` owns one or more ``Param.kind`` strings (a Coulomb plug-in owns ``coulomb`` and its
asymmetry and Stribeck terms) and overrides the hooks that apply to it; the rest do nothing.

==================  ============================================================================
hook                who calls it
==================  ============================================================================
``declares``        ``catalog.effect_params``: an effect parameter on every joint / actuator /
                    body (``attach``), neutral by default
``prepare, setup``  ``PhysicsModel.__init__``: structural model changes before ``put_model``;
                    static index data (and changes to the MJX model alone, ``pm.mx``)
``apply``           ``PhysicsModel.apply``: the ``mjx.Model`` fields a value changes (in ``order``)
``damping``         ``Effects.velocity_damping``: a velocity-dependent force written as damping
                    (implicit in MuJoCo's integrator, so stiff laws stay stable)
``force``           ``Effects.constant_force``: a generalised force independent of the state,
                    held over the control step (``qfrc_applied``)
``command``         ``Effects.actuate``: a stage of the command path, in ``command_order``
                    (delay line 10 -> motor lag 20 -> backlash 30), with its own memory
                    (``command_state``; ``push`` once per control step; ``rebase`` where the
                    joint velocities it ran with are corrected: ``sysid.shooting``;
                    ``activation`` where it sets an actuator's activation: ``Effects.activation``;
                    ``command_off``, what it passes on while off, where a replay leaves it out:
                    ``skip_when_off``)
``sense``           ``Effects.sense`` / ``measure`` / ``unsense``: how a measured position is made
``export``          ``sysid.export``: the fitted value written into the user's ``MjSpec``
``candidates``      ``sysid.candidates.library``: the hypotheses the diagnosis searches
==================  ============================================================================
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

    def declared(self, m: mujoco.MjModel, index: int, kind: str, entry: tuple) -> tuple:
        """``declares[kind]`` as declared on object ``index`` of ``m``: a kind whose model does
        not hold on some objects narrows the bounds there to the neutral value, so a value or a
        randomisation range that asks for it is refused by the bounds rule (``physics/params.py``)."""
        return entry

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

    def force_setup(self, m: mujoco.MjModel, spec):
        """``(dof indices [J], static data)`` for ``force``, or None when this kind adds none."""
        return None

    def force(self, data, z):
        """``[J]`` generalised force on its dofs (N or N m), constant over the control step."""
        raise NotImplementedError

    # ------------------------------------------------- command path and sensing -------
    # A stage of the command path sees the command after the stages before it (``command_order``)
    # and keeps its memory in the effect state under its first ``owns`` name.
    command_order: float | None = None

    def command_setup(self, m: mujoco.MjModel, spec, cfg):
        """Static data for ``command``, or None when this kind is not on this model's command path."""
        return None

    def command_state(self, data, ctrl):
        """Its memory with the drive at rest under ``ctrl [nu]`` (a pytree; zeros: a fresh start)."""
        return ()

    def push(self, data, state, ctrl):
        """A new command ``[nu]`` arrives (once per control step)."""
        return state

    def command(self, data, z, state, u, j, n: int, qpos, h: float, qvel=None):
        """``(u [nu], state)`` for physics sub-step ``j`` of ``n`` (``h`` seconds; ``qpos [nq]``,
        ``qvel [nv]``: the true state at the sub-step's start; a stage whose ``sets_act`` is true
        also gets ``act=`` ``[na]``)."""
        raise NotImplementedError

    # A stage that must set an actuator's activation itself (a force that passes through an
    # integrating servo: the backlash) keeps the value in its memory and writes it here, once per
    # sub-step, after the command path has run.
    def sets_act(self, data) -> bool:
        """Whether ``activation`` changes anything on this model (static)."""
        return False

    def activation(self, data, state, act):
        """``act [na]`` as this stage sets it for the coming sub-step (unchanged by default)."""
        return act

    def command_rows(self, data) -> list[int]:
        """Rows of ``z`` whose value > 0 switches this stage on (its memory then matters)."""
        return []

    # a stage whose sums cost a replay of the command path much more than the others' (the
    # backlash's): ``sysid.shooting`` replays a batch in which it is off everywhere without it
    skip_when_off: bool = False

    def command_off(self, data, state, u):
        """``(u [nu], state)``: what ``command`` gives with every row of ``command_rows`` at 0, its
        memory left as it is (unused while the stage is off). Pass-through by default; a stage
        that also limits the command when off (the backlash's motor range) says so here."""
        return u, state

    def rebase(self, data, state, dv):
        """Its memory when the joint velocities it was run with change by ``dv [nv]``: a stage
        whose state moves with its joint (the backlash's motor side) moves with it; the rest keep
        theirs."""
        return state

    def sense_setup(self, m: mujoco.MjModel, spec):
        """Static data for ``sense``/``measure``/``unsense``, or None when this kind changes no measurement."""
        return None

    def sense(self, data, z, qpos, key):
        """Measured positions ``[nq]`` from ``qpos [nq]`` (``key``: for noise)."""
        raise NotImplementedError

    def measure(self, data, z, qpos):
        """Measured positions without noise."""
        raise NotImplementedError

    def unsense(self, data, z, qpos_meas):
        """True positions implied by measured ones (noise ignored)."""
        raise NotImplementedError

    # ---------------------------------------------------------------- sysid ------------
    def export(self, ctx, p, v: float) -> None:
        """Write parameter ``p`` at its fitted value ``v`` into ``ctx.spec`` (an ``MjSpec``)."""

    def candidates(self, system, sc, add, target: int) -> None:
        """Offer hypotheses for object ``target`` (joint / actuator / body id; -1 for global)
        through ``add(effect, target_name, params, grid, scales, search)``."""


def joint_dofs(m: mujoco.MjModel, j: int) -> np.ndarray:
    """The dofs of joint ``j`` (MuJoCo's ``dof_jntid``): a hinge's or slide's one, a ball joint's
    three (its angular velocity, body frame), a free joint's six."""
    return np.flatnonzero(m.dof_jntid == j)


def ctrl_limits(m: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's command clamp: ``(low [nu], high [nu])`` from ``ctrlrange``, +-inf where an
    actuator is not ``ctrllimited``."""
    limited = m.actuator_ctrllimited > 0
    return (np.where(limited, m.actuator_ctrlrange[:, 0], -np.inf),
            np.where(limited, m.actuator_ctrlrange[:, 1], np.inf))


_DIRECT = (int(mujoco.mjtTrn.mjTRN_JOINT), int(mujoco.mjtTrn.mjTRN_JOINTINPARENT))
# joints that turn every way (a drone's free joint, a ball): a gear on one is a direction, not a
# ratio (``gain.gear_size``), and a payload on the body they carry sits anywhere in its frame
TURNING = (int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_BALL))


def actuator_joint(m: mujoco.MjModel, a: int) -> int:
    """The joint actuator ``a`` drives directly (a joint transmission), or -1 where it pulls a
    tendon or pushes at a site (a thruster): its force then reaches the joints through moment
    arms that MuJoCo computes, so the command path's delay, lag and saturation act on it as on a
    joint's, while a dead band between a motor and *its* joint is not defined."""
    return int(m.actuator_trnid[a, 0]) if int(m.actuator_trntype[a]) in _DIRECT else -1


def actuator_is_linear(m: mujoco.MjModel, a: int) -> bool:
    """Its force is in N (a slide joint, a spatial tendon's length in m, a site's force), not N m
    (a hinge, a fixed tendon whose first joint is a hinge, a site's gear with a torque only)."""
    if int(m.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_SITE):
        return bool(np.any(m.actuator_gear[a, :3] != 0))
    j = actuator_joint(m, a)
    if j < 0 and int(m.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_TENDON):
        adr = int(m.tendon_adr[m.actuator_trnid[a, 0]])
        if int(m.wrap_type[adr]) != int(mujoco.mjtWrap.mjWRAP_JOINT):
            return True  # spatial
        j = int(m.wrap_objid[adr])
    return j >= 0 and m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE


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


def add_constant_force(ctx, param: str, name: str, joint: str, force: float) -> None:
    """Write fitted parameter ``param`` as actuator ``name``, whose force on ``joint`` is its bias
    ``force`` alone (gain 0: its ``ctrl`` does nothing), appended after the model's own so their
    ``ctrl`` indices do not change: how a constant force (a friction's asymmetry, a torque offset)
    is written into MJCF."""
    a = ctx.spec.add_actuator(name=name, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    a.gainprm[0] = 0.0
    a.biastype = mujoco.mjtBias.mjBIAS_AFFINE
    a.biasprm[:3] = [float(force), 0.0, 0.0]
    ctx.native(param, f"a constant force {float(force):.6g} on {joint} (actuator '{name}', bias only)")


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
