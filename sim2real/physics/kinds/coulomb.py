"""Coulomb friction (with a per-direction asymmetry and a Stribeck breakaway term) on a joint.

Written as ``f(v) = c(v) * v`` with ``c(v) = level(v) * tanh(v/eps) / v >= 0`` and added to the
joint's damping for the sub-step (``eps``: the joint's ``coulomb_vel`` where set, else the plant's
``coulomb_eps``): MuJoCo's integrators treat damping implicitly, so the stiff
region near ``v = 0`` stays stable for any ``eps`` and the joint sticks instead of chattering,
with no ``frictionloss`` structure in the compiled model (the MJX ``put_model`` pitfall).
"""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from sim2real.physics.kinds.base import JOINT, Kind, add_constant_force, joint_dofs, rows, take


class Coulomb(Kind):
    owns = ("coulomb", "coulomb_asym", "stribeck", "stribeck_vel", "coulomb_vel")
    attach = JOINT
    declares = {
        "coulomb": (0.0, 0.0, 1e4, "N|Nm", "Coulomb friction level Fc opposing joint motion"),
        "coulomb_asym": (0.0, -1.0, 1.0, "-", "asymmetry a: Fc(1+a) for positive, Fc(1-a) for negative velocity"),
        "stribeck": (0.0, 0.0, 1e4, "N|Nm", "extra breakaway friction Fs at zero velocity (Stribeck)"),
        "stribeck_vel": (0.1, 1e-4, 1e2, "m/s|rad/s", "Stribeck velocity vs: breakaway term decays as exp(-(v/vs)^2)"),
        "coulomb_vel": (0.0, 0.0, 1e2, "m/s|rad/s",
                        "speed over which the friction builds up to its level (tanh scale; 0: the plant's coulomb_eps)"),
    }
    order = 51
    effect = "coulomb_friction"

    def damping_setup(self, m, spec, cfg):
        # every dof of its joint (a ball joint's three, each with the level, as MuJoCo's frictionloss)
        dofs = np.array([d for _, p in spec.of_kind("coulomb") for d in joint_dofs(m, p.index)], np.int32)
        if not len(dofs):
            return None
        joints = m.dof_jntid[dofs]
        data = {k: rows(spec, k, joints) for k in self.owns}
        data["eps"] = cfg.coulomb_eps
        return dofs, data

    def damping(self, data, z, qvel):
        v = qvel
        fc, asym = take(z, data["coulomb"]), take(z, data["coulomb_asym"])
        fs, vs = take(z, data["stribeck"]), take(z, data["stribeck_vel"], 0.1)
        level = fc * (1.0 + asym * jnp.sign(v)) + fs * jnp.exp(-jnp.square(v / vs))
        ve = take(z, data["coulomb_vel"])
        eps = jnp.where(ve > 0, ve, data["eps"])
        safe_v = jnp.where(jnp.abs(v) > 1e-12, v, 1.0)
        c = jnp.where(jnp.abs(v) > 1e-12, level * jnp.tanh(v / eps) / safe_v, level / eps)
        return jnp.where(level > 0, c, 0.0)

    def export(self, ctx, p, v) -> None:
        # MuJoCo's frictionloss is the symmetric level Fc. The asymmetry is a constant force: the
        # friction -Fc(1+a) for v > 0 and +Fc(1-a) for v < 0 is -Fc sign(v) - a Fc, so -a Fc is
        # written as an actuator whose force is its bias alone (gain 0: its ctrl does nothing),
        # appended after the model's own (their ctrl indices unchanged). At rest the pair breaks
        # away at Fc(1+a) one way and Fc(1-a) the other, as the fitted law does. Stribeck: <numeric>.
        jn = ctx.system.joints[p.index]
        if p.kind == "coulomb" and (v > 0 or p.default > 0):
            # MuJoCo's friction is a soft constraint; at its default time constant (0.02 s) a
            # stuck joint creeps and every stop is softened, which the fitted law does not do
            # (an arm under PD control ends 0.06 rad apart within 50 ms). Two physics steps is the
            # hardest MuJoCo simulates stably.
            j = ctx.spec.joint(jn)
            j.frictionloss = v
            j.solref_friction = [2.0 * float(ctx.spec.option.timestep), 1.0]
            ctx.native(p.name, f"frictionloss with solreffriction=\"{2.0 * float(ctx.spec.option.timestep):.6g} 1\" "
                               "(MuJoCo's hardest: its default 0.02 s softens the stops the fitted law makes)")
        elif p.kind == "coulomb_asym" and v != 0 and ctx.values.get(f"coulomb:{jn}", 0.0) > 0:
            add_constant_force(ctx, p.name, f"sim2real_friction_offset:{jn}", jn, -v * ctx.values[f"coulomb:{jn}"])
        elif p.kind == "coulomb_vel" and v > 0:
            ctx.only_numeric(p.name, "MuJoCo's friction has no onset speed")
        elif p.kind == "stribeck" and v > 0:
            ctx.only_numeric(p.name, "MuJoCo's friction has no breakaway (Stribeck) term")

    def candidates(self, system, sc, add, target) -> None:
        jn = system.joints[target]
        if system.declared_friction(jn):  # a declared frictionloss is re-fitted as a nominal parameter
            return
        c, v = sc.force[target], sc.speed[target]
        # the level, and the speed over which it builds up: friction that sticks harder than the
        # plant's default smoothing, or one that is soft (pre-sliding; MuJoCo's own frictionloss
        # is a soft constraint). The tuning half named 2 more friction cases with it fitted.
        eps = system.effects.cfg.coulomb_eps
        add("coulomb_friction", jn, [f"coulomb:{jn}", f"coulomb_vel:{jn}"],
            [(f * c, e) for f in (0.03, 0.1, 0.3) for e in (eps, 0.1 * v)], [0.1 * c, 0.1 * v],
            [(0.0, 2.0 * c), (0.1 * eps, v)])
