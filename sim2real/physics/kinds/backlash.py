"""Backlash: a dead band between an actuator and its joint, crossed by the motor side's inertia
(the command path's last stage)."""
from __future__ import annotations

import jax.numpy as jnp
import mujoco
import numpy as np

from sim2real._mjx import mjx
from sim2real.physics.kinds.base import ACTUATOR, Kind, actuator_is_linear, actuator_joint, ctrl_limits, name_of, rows, take
from sim2real.physics.kinds.gain import nominal_gain
from sim2real.physics.params import Param


def motor_side_params(m: mujoco.MjModel, actuators, default: float = 1e-2) -> list[Param]:
    """``backlash_inertia:<act>`` then ``backlash_stiffness:<act>`` for every actuator (reflected to
    the joint). The inertia of the motor side crossing the dead band defaults to the joint's
    armature, or ``default`` where it has none (the effects library's fixed guess), so the default
    is neutral; the mesh's stiffness beyond the band defaults to 0, a rigid mesh."""
    inertia, stiffness = [], []
    for a in actuators:
        j = actuator_joint(m, a)
        arm = float(m.dof_armature[m.jnt_dofadr[j]]) if j >= 0 else 0.0
        slide = actuator_is_linear(m, a)
        name = name_of(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a)
        inertia.append(Param(f"backlash_inertia:{name}", arm if arm > 0 else default, 1e-7, 1e4,
                             "kg" if slide else "kg m^2", "inertia of the motor side crossing the backlash band",
                             "backlash_inertia", a))
        stiffness.append(Param(f"backlash_stiffness:{name}", 0.0, 0.0, 1e9, "N/m" if slide else "Nm/rad",
                               "stiffness of the mesh beyond the backlash band (0: rigid)", "backlash_stiffness", a))
    return inertia + stiffness


# damping ratio of the motor side's mode on a compliant mesh (a common modelling choice for a gear
# mesh; the independent benchmark's generator makes the same one)
MESH_DAMPING_RATIO = 0.5


class Backlash(Kind):
    """A dead band of width ``b`` between an actuator and its joint, crossed by the motor side.

    The motor side is a state of its own: its position relative to the joint, ``gap`` in
    ``[-b/2, b/2]``, and its velocity ``w`` (joint units). The actuator's law acts on it -- a
    motor's torque ``G u``; a servo's ``G u - K (q + gap) - D w``, with the joint's ``K``/``D``
    from its bias -- over the motor side's inertia ``J`` (``backlash_inertia``). Inside the band
    the joint feels nothing (the command sent to MuJoCo is the one whose actuator force is zero)
    and the band moves with the joint (``gap' = w - qdot``); at an edge the motor side's momentum
    relative to the joint, ``J (w - qdot)``, passes to the joint in that sub-step (an inelastic
    impact, ``J`` small against the joint's own inertia) and the two then move together, the
    actuator's force reaching the joint, until it pulls away from the edge. The motor side is
    integrated implicitly (a stiff servo on a light rotor stays stable at any sub-step). Actuators
    with a filter (``dyntype="filter"``) pass this stage's output through it: a fast filter
    delays the band's force a little. An integrating servo (``intvelocity``: ``act' = u``, force
    ``G act - K q - D qdot``) acts on the motor side through its setpoint, so there this stage
    integrates the command itself (``s``, from the activation MuJoCo held when it started, within
    ``actrange``), lets the law act on ``s``, and hands the joint its force by setting the
    activation (``activation``; MuJoCo's own integration of ``u`` is overwritten each sub-step).

    MuJoCo clamps every command to its ``ctrlrange`` after the command path. The motor's own
    command is limited so, but the command this stage computes to pass a mesh force or an
    impact to the joint is not a motor command: clamped, the joint would get less than the
    motor side gives up. So where a backlash is in the spec, MJX's clamp is switched off
    (``setup``) and this stage clamps its input, every actuator's, instead: the same physics
    wherever the band is off.
    """

    owns = ("backlash", "backlash_inertia", "backlash_stiffness")
    attach = ACTUATOR
    declares = {"backlash": (0.0, 0.0, 1.0, "m|rad", "dead band width between the actuator and its joint")}
    order = 61
    effect = "backlash"
    candidate_order = 64
    command_order = 30
    skip_when_off = True   # its sums are nine tenths of a replay of the command path

    def declared(self, m, index, kind, entry):
        # on a tendon or a site (no joint of its own) the band is not defined: only 0 is allowed
        if kind == "backlash" and actuator_joint(m, index) < 0:
            d, lo, hi, unit, doc = entry
            return d, lo, d, unit, doc + " (0 on a tendon's or a site's actuator, which has no joint of its own)"
        return entry

    def setup(self, pm) -> None:
        # only the MJX model: native runs of the same model get raw commands, which MuJoCo clamps
        if pm.spec.of_kind("backlash"):
            pm.mx = pm.mx.replace(opt=pm.mx.opt.replace(
                disableflags=pm.mx.opt.disableflags | mjx.DisableBit.CLAMPCTRL))

    def command_setup(self, m, spec, cfg):
        acts = np.arange(m.nu)
        r = rows(spec, "backlash", acts)
        if not (r >= 0).any():
            return None
        # (a tendon's actuator: joint 0 stands in, its band held at 0 by ``declared``)
        joint = np.array([max(actuator_joint(m, a), 0) for a in acts], np.int32)
        arm = np.array([m.dof_armature[m.jnt_dofadr[j]] for j in joint])
        gear = np.array([m.actuator_gear[a, 0] for a in acts])
        g0 = np.array([nominal_gain(m, a) for a in acts])
        affine = np.array([m.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_AFFINE for a in acts])
        # the bias law in joint units: -K q - D qdot (a servo's stiffness, a damping bias)
        K = np.where(affine, -gear**2 * m.actuator_biasprm[:, 1], 0.0) if m.nu else np.zeros(0)
        D = np.where(affine, -gear**2 * m.actuator_biasprm[:, 2], 0.0) if m.nu else np.zeros(0)
        # the motor's command range: MuJoCo's clamp, which ``setup`` switches off in MJX
        lo, hi = ctrl_limits(m)
        # integrating servos: the setpoint is this stage's (class docstring), in ``actrange``
        integ = np.array([m.actuator_dyntype[a] == mujoco.mjtDyn.mjDYN_INTEGRATOR and actuator_joint(m, a) >= 0
                          for a in acts], bool)
        act_limited = np.array([bool(m.actuator_actlimited[a]) for a in acts], bool)
        return {
            "integ": integ,
            "actadr": np.array([max(m.actuator_actadr[a] + m.actuator_actnum[a] - 1, 0) for a in acts], np.int32),
            "act_lo": np.where(act_limited, m.actuator_actrange[:, 0], -np.inf) if m.nu else np.zeros(0),
            "act_hi": np.where(act_limited, m.actuator_actrange[:, 1], np.inf) if m.nu else np.zeros(0),
            "gear": gear,
            "rows": r,
            # the motor side's inertia may be a parameter too (the diagnosis fits it); else the static guess
            "inertia_rows": rows(spec, "backlash_inertia", acts),
            "stiffness_rows": rows(spec, "backlash_stiffness", acts),
            "inertia": (np.full(m.nu, cfg.backlash_inertia) if cfg.backlash_inertia > 0 else np.where(arm > 0, arm, 1e-2)),
            "gain_rows": rows(spec, "actuator_gain", acts),
            "gain": g0,
            # K follows a fitted gain (it is the servo's Kp); D stays as declared
            "k_per_gain": np.where(np.abs(g0) > 0, K / np.where(np.abs(g0) > 0, g0, 1.0), 0.0),
            "damp": D,
            "qpos": np.array([m.jnt_qposadr[j] for j in joint], np.int32),
            "dof": np.array([m.jnt_dofadr[j] for j in joint], np.int32),
            "ctrl_lo": lo,
            "ctrl_hi": hi,
        }

    def command_state(self, data, ctrl):
        """``(gap, w, s, started, act_out, sets) [nu] each``: the motor side's position inside the
        band relative to its joint and its velocity (joint units; at rest, centred); an integrating
        servo's setpoint (actuator length), 1 once it has been taken from the activation, and the
        activation this stage sets (where ``sets`` is 1)."""
        nu = len(data["rows"])
        return (jnp.zeros(nu),) * 6

    def command(self, data, z, state, u, j, n, qpos, h, qvel=None, act=None):
        gap, w, s, started, _, _ = state
        u = jnp.clip(u, data["ctrl_lo"], data["ctrl_hi"])  # the motor's command, limited as MuJoCo would
        integ = data["integ"]
        if integ.any():
            # an integrating servo holds where it starts: its setpoint is MuJoCo's activation then
            held = (act[data["actadr"]] if act is not None and act.shape[0] else data["gear"] * qpos[data["qpos"]])
            s = jnp.where(started > 0, s, held)
            x = jnp.where(integ, s, u)   # what the actuator's gain multiplies
        else:
            x = u
        b = take(z, data["rows"])
        half = 0.5 * b
        q = qpos[data["qpos"]]
        v = qvel[data["dof"]] if qvel is not None else jnp.zeros_like(q)
        G = jnp.where(data["gain_rows"] >= 0, take(z, data["gain_rows"]), data["gain"])
        K, D = G * data["k_per_gain"], data["damp"]
        J = jnp.maximum(jnp.where(data["inertia_rows"] >= 0, take(z, data["inertia_rows"], 1.0), data["inertia"]), 1e-9)
        k = jnp.maximum(take(z, data["stiffness_rows"], 0.0), 0.0)
        c = 2.0 * MESH_DAMPING_RATIO * jnp.sqrt(k * J)
        G_safe = jnp.where(jnp.abs(G) > 1e-12, G, 1e-12)

        def ctrl_for(force):  # the command whose actuator force on the joint is ``force``
            return (force + K * q + D * v) / G_safe

        def step(kk, cc, e):
            """The motor side after one implicit step with a mesh spring ``kk`` (damping ``cc``)
            pulling its gap towards ``e``; ``(gap, w)``."""
            w1 = (J * w + h * (G * x - K * (q + gap - h * v) - kk * (gap - h * v - e) + cc * v)) / (
                J + h * h * (K + kk) + h * (D + cc))
            return gap + h * (w1 - v), w1

        # free: the motor side under the actuator's law alone
        g_free, w_free = step(0.0, 0.0, 0.0)
        # -- a rigid mesh: at an edge, the actuator pushing into it, the motor side moves with the joint
        edge = jnp.where(gap >= 0, half, -half)
        push = G * x - K * (q + edge) - D * v
        engaged = (jnp.abs(gap) >= half) & (push * jnp.sign(edge) > 0)
        hit = (g_free >= half) | (g_free <= -half)
        g_hit = jnp.clip(g_free, -half, half)
        impulse = J * (w_free - v) / h                    # the relative momentum, passed on in this sub-step
        force_hit = impulse + G * x - K * (q + g_hit) - D * v
        u_rigid = jnp.where(engaged, x - K * edge / G_safe,
                            jnp.where(hit, ctrl_for(force_hit), ctrl_for(jnp.zeros_like(u))))
        gap_rigid = jnp.where(engaged, edge, jnp.where(hit, g_hit, g_free))
        w_rigid = jnp.where(engaged | hit, v, w_free)
        # -- a compliant mesh: beyond the band a spring; engaged on the side the motor side is (or goes)
        side = jnp.where(jnp.abs(gap) > half, jnp.sign(gap), jnp.sign(g_free))
        e = side * half
        g_eng, w_eng = step(k, c, e)
        mesh = k * (g_eng - e) + c * (w_eng - v)
        # in contact at the step's end, pushing (a mesh does not pull)
        on_mesh = ((jnp.abs(gap) > half) | (jnp.abs(g_free) > half)) & (side * (g_eng - e) > 0) & (side * mesh > 0)
        u_comp = jnp.where(on_mesh, ctrl_for(mesh), ctrl_for(jnp.zeros_like(u)))
        gap_comp = jnp.where(on_mesh, g_eng, jnp.clip(g_free, -half, half))
        w_comp = jnp.where(on_mesh, w_eng, w_free)
        rigid = k <= 0
        u_out = jnp.where(rigid, u_rigid, u_comp)
        gap_new = jnp.where(rigid, gap_rigid, gap_comp)
        w_new = jnp.where(rigid, w_rigid, w_comp)
        on = b > 0
        sets = on & integ
        # the integrating servo's own integration (MuJoCo's, Euler then clamped), within its range
        s_new = jnp.clip(s + h * u, data["act_lo"], data["act_hi"])
        return jnp.where(on & ~integ, u_out, u), (
            jnp.where(on, gap_new, gap), jnp.where(on, w_new, w), jnp.where(integ, s_new, s),
            jnp.ones_like(started), jnp.where(sets, u_out, 0.0), sets.astype(u.dtype))

    def command_rows(self, data):
        return [int(r) for r in data["rows"] if r >= 0]

    def command_off(self, data, state, u):
        # with every band at 0 ``command`` passes the command limited to its range, and nothing
        # it keeps (the motor side, an integrating servo's setpoint) reaches the output
        return jnp.clip(u, data["ctrl_lo"], data["ctrl_hi"]), state

    def sets_act(self, data) -> bool:
        return bool(data["integ"].any())

    def activation(self, data, state, act):
        if not self.sets_act(data):
            return act
        idx = np.where(data["integ"])[0]
        adr = data["actadr"][idx]
        act_out, sets = state[4][idx], state[5][idx]
        return act.at[adr].set(jnp.where(sets > 0, act_out.astype(act.dtype), act[adr]))

    def rebase(self, data, state, dv):
        # the motor side's velocity was computed against the joint's (estimated) velocity: where
        # that estimate is corrected, the motor side it dragged along is corrected by as much
        gap, w, *rest = state
        return (gap, w + dv[data["dof"]], *rest)

    def candidates(self, system, sc, add, target) -> None:
        m = system.mj
        an = system.actuators[target]
        j = actuator_joint(m, target)
        if system.spec[f"backlash:{an}"].high <= 0:  # (``declared``: a tendon or a site)
            how = "pushes at a site" if int(m.actuator_trntype[target]) == int(mujoco.mjtTrn.mjTRN_SITE) else "pulls a tendon"
            note = f"backlash not searched on {an}: it {how}, not a joint of its own"
            if note not in system.notes:
                system.notes.append(note)
            return
        # the dead band's width, the inertia of the motor side that crosses it (a few percent of
        # the joint's own, unknown: fitted) and the mesh's stiffness: rigid, or the joint ringing
        # against it at tens of Hz (a gear train's compliance)
        slide = m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
        widths = np.geomspace(4e-5, 2e-3, 4) if slide else np.geomspace(0.004, 0.06, 4)
        J = float(sc.inertia[j]) if sc.inertia is not None else 1e-2
        params = [f"backlash:{an}", f"backlash_inertia:{an}"]
        if f"backlash_stiffness:{an}" in system.spec:
            params.append(f"backlash_stiffness:{an}")
            # rigid, and compliant (the joint ringing at 25 Hz): the fit moves all three. Fits start
            # compliant (``select.band_starts``) and stay so, the mesh ringing at 2.5-200 Hz: 0 is
            # not the soft end of the stiffness but another model, the rigid mesh, and a step
            # clipped to it jumps there (an arm's shoulder band: 9 mrad at 0, 30 mrad and 339
            # N m/rad from the same start when it was not reached; ``tuning.md`` step 79)
            def ringing(hz):  # the mesh stiffness at which the joint rings at ``hz``
                return J * (2 * np.pi * hz) ** 2
            grid = [(w, 0.03 * J, k) for w in widths for k in (0.0, ringing(25.0))]
            scales = [float(widths[1]), 0.03 * J, ringing(25.0)]
            search = [(0.25 * float(widths[0]), float(widths[-1])), (1e-4 * J, 2.0 * J), (ringing(2.5), ringing(200.0))]
        else:
            grid = [(w, f * J) for w in widths for f in (0.01, 0.1)]
            scales = [float(widths[1]), 0.03 * J]
            search = [(0.25 * float(widths[0]), float(widths[-1])), (1e-4 * J, 2.0 * J)]
        add("backlash", an, params, grid, scales, search)
