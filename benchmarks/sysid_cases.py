"""Independent cases for the diagnosis: native MuJoCo truth, effects written here, fresh MJCF.

Nothing in this file imports ``sim2real``: the "true" plants are written as new MJCF (not the
envs' assets), stepped with MuJoCo's own ``mj_step``, and every hidden effect is implemented here
on its own terms -- MuJoCo's ``frictionloss`` for Coulomb friction, native damping, springs and
force limits, a payload as an extra welded body, a delay line and a first-order lag run at the
truth's physics rate, backlash as a separate motor-side rotor coupled to the link through a dead
band, sensor offsets and noise added to what is logged. The diagnosis only ever sees the nominal
MJCF (written as people write it: masses from geoms or ``<inertial>``, any integrator, no helper
sites) and the CSV recordings.

    cases = build_cases()                 # the frozen list (seeds, designs, truths), ~160 cases
    paths = generate(cases[0], folder)    # nominal.xml, train_0.csv, train_1.csv, heldout.csv, truth.json

``split``: a case with an even seed belongs to the tuning half, an odd seed to the test half.
Cases come in pairs of neighbouring seeds (same system and effect, other magnitude and design),
so both halves cover the same conditions. ``build_cases(extra=True)`` draws a second list by the
same recipe from other seeds (1000 and up, split ``extra``): 144 more cases for tuning, made after
the tuning half had been looked at many times, so a change can be checked on cases nothing was
tuned on before it is kept. It is not part of the frozen list (its fingerprint is not the test's).
``focus_cases()`` is a third tuning list (seeds 3000 and up, split ``focus``), made when backlash
and payloads were the kinds the diagnosis missed most on both tuning lists: every system's
backlash and payload targets, twice each, by the same designs and magnitudes.
``pair_cases()`` is a fourth tuning list (seeds 3500 and up, split ``pairs``): a backlash and a
Coulomb friction on the same joint, on every system that can have both. ``servo_cases()``,
``beside_cases()``, ``timing_cases()`` (every system's action delay) and ``combos_cases()`` (every
pair of kinds but backlash + friction on every system; seeds 6000 and up, past the fresh list's)
are the fifth to eighth tuning lists.
``build_cases(fresh=True)`` is a second *test* list (seeds 4000 and up, split ``fresh``), drawn by
the same recipe on 2026-11-28 and frozen (``results/diagnosis_independent/cases_fresh_frozen.json``)
before it was run once: the first test half had been looked at thirty times by then, and a
figure from a list looked at that often is partly a tuning figure. Nothing is tuned on it.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os

import mujoco
import numpy as np

# bumped whenever the generated data change (the case list is frozen separately: fingerprint())
GENERATOR_VERSION = 2
INTEGRATORS = ("Euler", "implicit", "implicitfast", "RK4")
RATES = (100.0, 200.0, 500.0, 1000.0)
EXCITATIONS = ("multisine", "chirp", "prbs", "steps", "pd")
EXTRA_SEED = 1000  # first seed of the extra (tuning) list: build_cases(extra=True)
FOCUS_SEED = 3000  # first seed of the focus (tuning) list: focus_cases()
PAIRS_SEED = 3500  # first seed of the backlash + friction (tuning) list: pair_cases()
SERVO_SEED = 3700  # first seed of the integrating-servo backlash (tuning) list: servo_cases()
BESIDE_SEED = 3800  # first seed of the drive-effects (tuning) list: beside_cases()
TIMING_SEED = 3900  # first seed of the action-delay (tuning) list: timing_cases()
COMBOS_SEED = 6000  # first seed of the two-effect (tuning) list: combos_cases() (after the fresh list's seeds)
PD_SEED = 7000  # first seed of the PD-loop timing (tuning) list: pd_cases()
FRESH_SEED = 4000  # first seed of the fresh test list: build_cases(fresh=True)


# ------------------------------------------------------------------------------------------------
# systems: links (bodies with one joint each) and actuators, as plain data
@dataclasses.dataclass
class Link:
    name: str
    parent: str                 # "world" or another link's name
    pos: tuple                  # body position in the parent frame
    joint: str                  # joint name
    jtype: str                  # "hinge" | "slide"
    axis: tuple
    geom: dict                  # {"type": "capsule", "fromto": (...), "size": r} or box/cylinder with "pos"
    mass: float
    damping: float = 0.0        # declared joint damping (the nominal model's)
    stiffness: float = 0.0      # declared spring
    tip: tuple | None = None    # where a payload goes (link frame); None: no payload candidate


@dataclasses.dataclass
class Actuator:
    name: str
    joint: str
    kind: str                   # motor | position | velocity | intvelocity | general
    gear: float = 1.0
    kp: float = 0.0
    kv: float = 0.0
    gain: float = 0.0           # general: force = gain * act/ctrl + bias1 * q + bias2 * qdot
    bias: tuple = (0.0, 0.0)
    dyn_tau: float = 0.0        # general with dyntype=filter (a lag the user *knows* about)
    ctrlrange: tuple = (-1.0, 1.0)


@dataclasses.dataclass
class System:
    name: str
    links: list
    actuators: list
    gravity: tuple = (0.0, 0.0, -9.81)
    # open-loop references for servos are in these units (ctrl range is the limit)
    pd: tuple | None = None     # (kp, kd) per actuated joint for the generator's own PD loop
    unobservable: tuple = ()    # effect kinds the data cannot show on this system (never hidden here)
    max_range: float | None = None  # open-loop motion allowed per joint (default: 4 rad, 0.5 m); None: any


def _cap(length, r=0.02, axis="z"):
    to = {"z": (0, 0, -length), "x": (length, 0, 0)}[axis]
    return {"type": "capsule", "fromto": (0, 0, 0) + to, "size": r}


def systems() -> dict[str, System]:
    """The plants. Lengths in m, masses in kg, gains in SI units."""
    S = {}
    S["pendulum_geared"] = System(
        "pendulum_geared",
        [Link("link", "world", (0, 0, 0), "hinge", "hinge", (0, 1, 0), _cap(0.3), 0.4, damping=0.01,
              tip=(0, 0, -0.3))],
        [Actuator("motor", "hinge", "motor", gear=20.0, ctrlrange=(-0.1, 0.1))],
        pd=((4.0, 0.25),))
    S["rc_servo_pendulum"] = System(
        "rc_servo_pendulum",
        [Link("arm", "world", (0, 0, 0), "servo_joint", "hinge", (0, 1, 0), _cap(0.15, 0.01), 0.08,
              tip=(0, 0, -0.15))],
        [Actuator("servo", "servo_joint", "position", kp=2.0, kv=0.04, ctrlrange=(-1.5, 1.5))])
    S["arm2"] = System(
        "arm2",
        [Link("upper", "world", (0, 0, 0), "shoulder", "hinge", (0, 1, 0), _cap(0.3), 0.6, damping=0.02,
              tip=(0, 0, -0.3)),
         Link("lower", "upper", (0, 0, -0.3), "elbow", "hinge", (0, 1, 0), _cap(0.25), 0.3, damping=0.01,
              tip=(0, 0, -0.25))],
        [Actuator("m_shoulder", "shoulder", "motor", gear=1.0, ctrlrange=(-4, 4)),
         Actuator("m_elbow", "elbow", "motor", gear=1.0, ctrlrange=(-2, 2))],
        pd=((25.0, 1.2), (8.0, 0.35)))
    S["arm3"] = System(
        "arm3",
        [Link("l1", "world", (0, 0, 0), "j1", "hinge", (0, 1, 0), _cap(0.25), 0.5, damping=0.02, tip=(0, 0, -0.25)),
         Link("l2", "l1", (0, 0, -0.25), "j2", "hinge", (0, 1, 0), _cap(0.2), 0.3, damping=0.01, tip=(0, 0, -0.2)),
         Link("l3", "l2", (0, 0, -0.2), "j3", "hinge", (0, 1, 0), _cap(0.15), 0.15, damping=0.005,
              tip=(0, 0, -0.15))],
        [Actuator("a1", "j1", "motor", ctrlrange=(-5, 5)), Actuator("a2", "j2", "motor", ctrlrange=(-3, 3)),
         Actuator("a3", "j3", "motor", ctrlrange=(-1.5, 1.5))],
        pd=((30.0, 1.5), (12.0, 0.5), (4.0, 0.12)))
    S["pendubot"] = System(
        "pendubot",
        [Link("first", "world", (0, 0, 0), "j_act", "hinge", (0, 1, 0), _cap(0.2), 0.3, damping=0.01, tip=(0, 0, -0.2)),
         Link("second", "first", (0, 0, -0.2), "j_free", "hinge", (0, 1, 0), _cap(0.2), 0.2,
              tip=(0, 0, -0.2))],
        [Actuator("motor", "j_act", "motor", gear=1.0, ctrlrange=(-1.5, 1.5))])
    S["scara"] = System(  # horizontal arm: gravity along the joint axes, no gravity torque
        "scara",
        [Link("inner", "world", (0, 0, 0), "base", "hinge", (0, 0, 1), _cap(0.3, axis="x"), 0.8, damping=0.03,
              tip=(0.3, 0, 0)),
         Link("outer", "inner", (0.3, 0, 0), "elbow", "hinge", (0, 0, 1), _cap(0.25, axis="x"), 0.4,
              tip=(0.25, 0, 0))],
        [Actuator("m_base", "base", "motor", ctrlrange=(-2, 2)), Actuator("m_elbow", "elbow", "motor", ctrlrange=(-1, 1))],
        unobservable=("sensor_offset",))
    S["cartpole"] = System(
        "cartpole",
        [Link("cart", "world", (0, 0, 0), "slider", "slide", (1, 0, 0),
              {"type": "box", "size": (0.1, 0.05, 0.03), "pos": (0, 0, 0)}, 1.0, damping=0.1),
         Link("pole", "cart", (0, 0, 0), "hinge", "hinge", (0, 1, 0), _cap(0.5, 0.015), 0.15, damping=0.002,
              tip=(0, 0, -0.5))],
        [Actuator("push", "slider", "motor", gear=10.0, ctrlrange=(-1, 1))],
        unobservable=("sensor_offset@slider", "payload@cart"))
    S["gantry_crane"] = System(  # trolley on a position servo, load hanging on a rope
        "gantry_crane",
        [Link("trolley", "world", (0, 0, 0), "travel", "slide", (1, 0, 0),
              {"type": "box", "size": (0.08, 0.05, 0.03), "pos": (0, 0, 0)}, 2.0, damping=0.5),
         Link("load", "trolley", (0, 0, 0), "swing", "hinge", (0, 1, 0), _cap(0.6, 0.01), 0.5, damping=0.005,
              tip=(0, 0, -0.6))],
        [Actuator("servo", "travel", "position", kp=400.0, kv=60.0, ctrlrange=(-0.5, 0.5))],
        unobservable=("payload@trolley",))
    S["linear_axis"] = System(  # EMPS-like drive under a stiff position servo
        "linear_axis",
        [Link("carriage", "world", (0, 0, 0), "axis", "slide", (1, 0, 0),
              {"type": "box", "size": (0.06, 0.06, 0.04), "pos": (0, 0, 0)}, 5.0, damping=20.0)],
        [Actuator("drive", "axis", "position", kp=4.0e4, kv=600.0, ctrlrange=(-0.1, 0.3))],
        unobservable=("payload",))
    S["ball_screw"] = System(  # motor torque through a 2 mm lead screw (gear = 2*pi/lead)
        "ball_screw",
        [Link("nut", "world", (0, 0, 0), "screw", "slide", (1, 0, 0),
              {"type": "box", "size": (0.05, 0.05, 0.05), "pos": (0, 0, 0)}, 8.0, damping=80.0)],
        [Actuator("motor", "screw", "motor", gear=2 * math.pi / 0.002, ctrlrange=(-0.1, 0.1))],
        unobservable=("sensor_offset", "payload", "joint_stiffness"), pd=((1500.0, 100.0),))
    S["belt_stage"] = System(  # voltage-driven DC motor: force = k*V - k_emf*v (back EMF)
        "belt_stage",
        [Link("slide", "world", (0, 0, 0), "belt", "slide", (1, 0, 0),
              {"type": "box", "size": (0.05, 0.04, 0.02), "pos": (0, 0, 0)}, 1.5, damping=2.0)],
        [Actuator("voltage", "belt", "general", gain=4.0, bias=(0.0, -6.0), ctrlrange=(-12, 12))],
        unobservable=("sensor_offset", "payload"), pd=((400.0, 40.0),))
    S["flywheel"] = System(  # disk on a vertical axis under a velocity servo
        "flywheel",
        [Link("wheel", "world", (0, 0, 0), "spin", "hinge", (0, 0, 1),
              {"type": "cylinder", "size": (0.1, 0.01), "pos": (0, 0, 0)}, 1.2, damping=0.002)],
        [Actuator("vservo", "spin", "velocity", kv=0.05, ctrlrange=(-30, 30))],
        unobservable=("sensor_offset", "payload", "joint_stiffness"), max_range=1e9)
    S["voice_coil"] = System(  # mass on a spring driven by a voice coil
        "voice_coil",
        [Link("mover", "world", (0, 0, 0), "coil", "slide", (1, 0, 0),
              {"type": "box", "size": (0.02, 0.02, 0.02), "pos": (0, 0, 0)}, 0.2, damping=0.8, stiffness=300.0)],
        [Actuator("coil", "coil", "motor", gear=5.0, ctrlrange=(-2, 2))],
        unobservable=("payload", "joint_stiffness"))
    S["intvel_pendulum"] = System(  # hinge driven by an integrated-velocity servo (a hobby servo's mode)
        "intvel_pendulum",
        [Link("bar", "world", (0, 0, 0), "pivot", "hinge", (0, 1, 0), _cap(0.2, 0.015), 0.25,
              tip=(0, 0, -0.2))],
        [Actuator("iservo", "pivot", "intvelocity", kp=6.0, kv=0.1, ctrlrange=(-3, 3))])
    S["filtered_drive"] = System(  # a general actuator whose lag the user already models (dyntype filter)
        "filtered_drive",
        [Link("rotor", "world", (0, 0, 0), "shaft", "hinge", (0, 1, 0), _cap(0.25), 0.5, damping=0.02,
              tip=(0, 0, -0.25))],
        [Actuator("amp", "shaft", "general", gain=3.0, dyn_tau=0.02, ctrlrange=(-1, 1))],
        pd=((3.0, 0.2),))
    return S


# ------------------------------------------------------------------------------------------------
# MJCF writing
def _f(v) -> str:
    return " ".join(f"{float(x):.9g}" for x in (v if isinstance(v, (tuple, list, np.ndarray)) else [v]))


def _geom_xml(g: dict, mass: float | None, name: str) -> str:
    attrs = [f'name="{name}"', f'type="{g["type"]}"', f'size="{_f(g["size"])}"']
    if "fromto" in g:
        attrs.append(f'fromto="{_f(g["fromto"])}"')
    if "pos" in g:
        attrs.append(f'pos="{_f(g["pos"])}"')
    if mass is not None:
        attrs.append(f'mass="{mass:.9g}"')
    return "<geom " + " ".join(attrs) + "/>"


@dataclasses.dataclass
class Mods:
    """What makes the truth differ from the nominal model (all native MuJoCo where possible)."""

    mass_scale: dict = dataclasses.field(default_factory=dict)      # link -> factor
    damping_scale: dict = dataclasses.field(default_factory=dict)   # joint -> factor (declared damping)
    extra_damping: dict = dataclasses.field(default_factory=dict)   # joint -> N s/m | Nm s/rad
    stiffness: dict = dataclasses.field(default_factory=dict)       # joint -> N/m | Nm/rad
    frictionloss: dict = dataclasses.field(default_factory=dict)    # joint -> N | Nm
    payload: dict = dataclasses.field(default_factory=dict)         # link -> (kg, position in link frame)
    forcerange: dict = dataclasses.field(default_factory=dict)      # actuator -> limit (actuator force units)
    rotor: dict = dataclasses.field(default_factory=dict)           # joint -> rotor inertia (backlash)


def _link_inertial(system: System, link: Link) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(pos, quat, diaginertia) of the link's geom-derived inertia, computed by MuJoCo itself."""
    xml = (f'<mujoco><worldbody><body name="b">{_geom_xml(link.geom, link.mass, "g")}'
           f'<joint type="hinge"/></body></worldbody></mujoco>')
    m = mujoco.MjModel.from_xml_string(xml)
    return m.body_ipos[1].copy(), m.body_iquat[1].copy(), m.body_inertia[1].copy()


def write_mjcf(system: System, integrator: str, timestep: float, mass_mode: str, mods: Mods | None = None,
               model_name: str = "") -> str:
    """MJCF text of the system (nominal when ``mods`` is None)."""
    mods = mods or Mods()
    children: dict[str, list[Link]] = {}
    for lk in system.links:
        children.setdefault(lk.parent, []).append(lk)

    def body(lk: Link, indent: str) -> list[str]:
        scale = mods.mass_scale.get(lk.name, 1.0)
        out = [f'{indent}<body name="{lk.name}" pos="{_f(lk.pos)}">']
        jd = lk.damping * mods.damping_scale.get(lk.joint, 1.0) + mods.extra_damping.get(lk.joint, 0.0)
        jattr = [f'name="{lk.joint}"', f'type="{lk.jtype}"', f'axis="{_f(lk.axis)}"']
        if jd > 0:
            jattr.append(f'damping="{jd:.9g}"')
        k = lk.stiffness + mods.stiffness.get(lk.joint, 0.0)
        if k > 0:
            jattr.append(f'stiffness="{k:.9g}"')
        if lk.joint in mods.frictionloss:
            jattr.append(f'frictionloss="{mods.frictionloss[lk.joint]:.9g}"')
        out.append(f'{indent}  <joint {" ".join(jattr)}/>')
        if mass_mode == "inertial":
            pos, quat, inertia = _link_inertial(system, lk)
            out.append(f'{indent}  <inertial pos="{_f(pos)}" quat="{_f(quat)}" mass="{lk.mass * scale:.9g}" '
                       f'diaginertia="{_f(inertia * scale)}"/>')
            out.append(f'{indent}  {_geom_xml(lk.geom, None, lk.name + "_geom")}')
        else:
            out.append(f'{indent}  {_geom_xml(lk.geom, lk.mass * scale, lk.name + "_geom")}')
        if lk.name in mods.payload:
            mp, where = mods.payload[lk.name]
            out.append(f'{indent}  <body name="{lk.name}_payload" pos="{_f(where)}">'
                       f'<inertial pos="0 0 0" mass="{mp:.9g}" diaginertia="{_f([1e-5 * mp] * 3)}"/></body>')
        for ch in children.get(lk.name, []):
            out += rotor(ch, indent + "  ")
            out += body(ch, indent + "  ")
        out.append(f"{indent}</body>")
        return out

    def rotor(lk: Link, indent: str) -> list[str]:
        """The motor side of a joint with backlash: coaxial body, driven by the actuator."""
        if lk.joint not in mods.rotor:
            return []
        return [f'{indent}<body name="{lk.joint}_rotor" pos="{_f(lk.pos)}">',
                f'{indent}  <joint name="{lk.joint}_rotor" type="{lk.jtype}" axis="{_f(lk.axis)}" '
                f'armature="{mods.rotor[lk.joint]:.9g}"/>',
                f'{indent}  <inertial pos="0 0 0" mass="1e-4" diaginertia="1e-9 1e-9 1e-9"/>',
                f"{indent}</body>"]

    lines = [f'<mujoco model="{model_name or system.name}">',
             f'  <option timestep="{timestep:.9g}" integrator="{integrator}" gravity="{_f(system.gravity)}"/>',
             '  <default><geom contype="0" conaffinity="0"/></default>', "  <worldbody>"]
    for lk in children.get("world", []):
        lines += rotor(lk, "    ")
        lines += body(lk, "    ")
    lines += ["  </worldbody>", "  <actuator>"]
    for a in system.actuators:
        joint = a.joint + "_rotor" if a.joint in mods.rotor else a.joint
        attr = [f'name="{a.name}"', f'joint="{joint}"', 'ctrllimited="true"', f'ctrlrange="{_f(a.ctrlrange)}"']
        if a.name in mods.forcerange:
            lim = mods.forcerange[a.name]
            attr += ['forcelimited="true"', f'forcerange="{-lim:.9g} {lim:.9g}"']
        if a.kind == "motor":
            lines.append(f'    <motor {" ".join(attr)} gear="{a.gear:.9g}"/>')
        elif a.kind == "position":
            lines.append(f'    <position {" ".join(attr)} kp="{a.kp:.9g}" kv="{a.kv:.9g}"/>')
        elif a.kind == "velocity":
            lines.append(f'    <velocity {" ".join(attr)} kv="{a.kv:.9g}"/>')
        elif a.kind == "intvelocity":
            lo, hi = a.ctrlrange
            lines.append(f'    <intvelocity {" ".join(attr)} kp="{a.kp:.9g}" kv="{a.kv:.9g}" actrange="-10 10"/>')
        elif a.kind == "general":
            dyn = f' dyntype="filter" dynprm="{a.dyn_tau:.9g}"' if a.dyn_tau > 0 else ""
            lines.append(f'    <general {" ".join(attr)}{dyn} gainprm="{a.gain:.9g}" biastype="affine" '
                         f'biasprm="0 {a.bias[0]:.9g} {a.bias[1]:.9g}"/>')
    lines += ["  </actuator>", "</mujoco>"]
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------------------------------------
# designs, truths, cases
@dataclasses.dataclass(frozen=True)
class Design:
    integrator: str
    timestep: float          # the nominal model's (s)
    mass_mode: str           # geom | inertial
    rate: float              # logging rate (Hz)
    seconds: float           # per recording
    excitation: str
    noise: float             # position noise std (rad; slides: m)
    quant: float             # encoder resolution (0: none)
    qvel: bool               # velocity column logged (noise 10x the position noise per second)


@dataclasses.dataclass(frozen=True)
class Case:
    seed: int
    system: str
    kind: str                # single | none | double
    effects: tuple           # ((effect, target, magnitude), ...): magnitude is a relative level 0, 1, 2
    nominal: tuple = ()      # param-only: (("mass", link, factor) | ("damping", joint, factor), ...)
    design: Design | None = None

    @property
    def split(self) -> str:
        if self.seed >= PD_SEED:
            return "pd"
        if self.seed >= COMBOS_SEED:
            return "combos"
        if self.seed >= FRESH_SEED:
            return "fresh"
        if self.seed >= TIMING_SEED:
            return "timing"
        if self.seed >= BESIDE_SEED:
            return "beside"
        if self.seed >= SERVO_SEED:
            return "servo"
        if self.seed >= PAIRS_SEED:
            return "pairs"
        if self.seed >= FOCUS_SEED:
            return "focus"
        if self.seed >= EXTRA_SEED:
            return "extra"
        return "tuning" if self.seed % 2 == 0 else "test"

    @property
    def label(self) -> str:
        what = "+".join(f"{e}@{t}" if t else e for e, t, _ in self.effects) or "none"
        return f"{self.seed:03d}_{self.system}_{what}"


def applicable(system: System) -> list[tuple[str, str]]:
    """(effect, target) pairs the data of this system can show."""
    out = []
    act_joints = {a.joint for a in system.actuators}
    for lk in system.links:
        out.append(("coulomb_friction", lk.joint))
        if lk.damping == 0:
            out.append(("viscous_damping", lk.joint))
        if lk.stiffness == 0:
            out.append(("joint_stiffness", lk.joint))
        out.append(("sensor_offset", lk.joint))
        if lk.tip is not None:
            out.append(("mass_offset", lk.name))
    out.append(("action_delay", ""))
    for a in system.actuators:
        out += [("motor_lag", a.name), ("actuator_saturation", a.name)]
        if a.joint in act_joints:
            out.append(("backlash", a.name))
    hidden = set(system.unobservable)

    def seen(e, t):
        names = {e, f"{e}@{t}"} | ({"payload", f"payload@{t}"} if e == "mass_offset" else set())
        return not names & hidden

    return [(e, t) for e, t in out if seen(e, t)]


def _design(system: System, rng: np.random.Generator, seconds: float | None = None) -> Design:
    integ = str(rng.choice(INTEGRATORS))
    ts = float(rng.choice([0.0005, 0.001, 0.002]))
    rate = float(rng.choice(RATES))
    exc = list(EXCITATIONS) if system.pd is not None else [e for e in EXCITATIONS if e != "pd"]
    slide = system.links[0].jtype == "slide"
    noise = float(rng.choice([1e-4, 3e-4, 1e-3, 3e-3]))
    quant = 0.0
    if rng.uniform() < 0.3:  # an encoder: quantised, little other noise
        quant = float(2 * math.pi / rng.choice([1024, 4096, 16384]))
        noise = 0.0
    if slide:  # linear scales: 0.01-0.3 mm noise, 1-10 um encoder steps
        noise, quant = noise * 0.1, (float(rng.choice([1e-6, 5e-6, 1e-5])) if quant else 0.0)
    return Design(integ, ts, str(rng.choice(["geom", "inertial"])), rate,
                  float(seconds if seconds is not None else rng.choice([3.0, 5.0, 8.0, 8.0, 12.0, 20.0])),
                  str(rng.choice(exc)), noise, quant, bool(rng.uniform() < 0.5))


def _case(seed: int, S: dict, system: str, kind: str, effects: tuple, nominal: tuple) -> Case:
    """One case; its design is drawn from its own seed, so a case does not depend on the list."""
    # (the fresh list's own stream: 1000 + seed would reuse the first list's parameter-only draws)
    rng = np.random.default_rng(1000 + seed if seed < FRESH_SEED else (seed, 20261128))
    return Case(seed, system, kind, effects, nominal, _design(S[system], rng))


def build_cases(extra: bool = False, fresh: bool = False) -> list[Case]:
    """The frozen case list (``extra``: the second list, same recipe, other seeds; ``fresh``: the
    second test list, the same recipe again). Deterministic: the same list on every machine."""
    S = systems()
    first = FRESH_SEED if fresh else EXTRA_SEED if extra else 0
    rng = np.random.default_rng(20261128 if fresh else 20261126 if extra else 20261123)
    cases: list[Case] = []

    def add_pair(system, kind, effects_pair, nominal_pair=((), ())):
        for k in range(2):
            cases.append(_case(first + len(cases), S, system, kind, effects_pair[k], nominal_pair[k]))

    # single effects: every applicable (effect, target) of a rotating subset of systems, in pairs
    singles = []
    for name, sysm in S.items():
        for e, t in applicable(sysm):
            singles.append((name, e, t))
    rng.shuffle(singles)
    # keep every effect kind well represented: up to 10 cases (5 pairs) per kind
    per_kind: dict[str, int] = {}
    chosen = []
    for name, e, t in singles:
        if per_kind.get(e, 0) >= 5:
            continue
        per_kind[e] = per_kind.get(e, 0) + 1
        chosen.append((name, e, t))
    for name, e, t in chosen:
        m = rng.permutation(3)[:2]
        add_pair(name, "single", (((e, t, int(m[0])),), ((e, t, int(m[1])),)))
    # parameter-only: masses and declared damping off, nothing missing (right answer: none)
    names = list(S)
    for i in range(16):
        name = names[i % len(names)]
        sysm = S[name]
        pair = []
        for k in range(2):
            r = np.random.default_rng(5000 + 10 * first + 2 * i + k)
            mods = []
            for lk in sysm.links:
                if r.uniform() < 0.7:
                    mods.append(("mass", lk.name, float(r.choice([0.7, 0.8, 1.25, 1.4]))))
                if lk.damping > 0 and r.uniform() < 0.5:
                    mods.append(("damping", lk.joint, float(r.choice([0.3, 0.5, 2.0, 3.0]))))
            if not mods:
                mods.append(("mass", sysm.links[0].name, 1.3))
            pair.append(tuple(mods))
        add_pair(name, "none", ((), ()), tuple(pair))
    # two effects at once
    doubles = []
    for name, sysm in S.items():
        app = applicable(sysm)
        kinds = {}
        for e, t in app:
            kinds.setdefault(e, []).append(t)
        for a, b in COMBOS:
            if a in kinds and b in kinds:
                ta = kinds[a][0]
                tb = kinds[b][-1] if a == b else kinds[b][0]
                if a == b and ta == tb:
                    continue
                doubles.append((name, (a, ta), (b, tb)))
    rng.shuffle(doubles)
    for name, (a, ta), (b, tb) in doubles[:12]:
        add_pair(name, "double", (((a, ta, 1), (b, tb, 2)), ((a, ta, 2), (b, tb, 1))))
    return cases


def focus_cases() -> list[Case]:
    """The focus list: a single backlash or payload on every target that can have one (not a
    backlash on an integrating servo, which the diagnosis did not model when the list was made),
    a pair of cases each (two of the three magnitudes, two designs). Deterministic."""
    S = systems()
    rng = np.random.default_rng(20261127)
    cases: list[Case] = []
    for name, sysm in S.items():
        integrating = {a.name for a in sysm.actuators if a.kind == "intvelocity"}
        for e, t in applicable(sysm):
            if e not in ("backlash", "mass_offset") or (e == "backlash" and t in integrating):
                continue
            m = rng.permutation(3)[:2]
            for k in range(2):
                cases.append(_case(FOCUS_SEED + len(cases), S, name, "single", ((e, t, int(m[k])),), ()))
    return cases


def pair_cases() -> list[Case]:
    """The pairs list (seeds 3500 and up, split ``pairs``), a fourth tuning list made on
    2026-11-28 when the fresh test list showed backlash pairs named least: on every actuator that
    could have a modelled backlash then (not an integrating servo), the backlash and a Coulomb
    friction on its own joint (a gearbox has both), twice each (magnitudes 1 + 2 and 2 + 1, as
    the pairs of ``build_cases``).
    Deterministic."""
    S = systems()
    cases: list[Case] = []
    for name, sysm in S.items():
        integrating = {a.name for a in sysm.actuators if a.kind == "intvelocity"}
        app = set(applicable(sysm))
        for a in sysm.actuators:
            if a.name in integrating or ("backlash", a.name) not in app or ("coulomb_friction", a.joint) not in app:
                continue
            for mb, mf in ((1, 2), (2, 1)):
                cases.append(_case(PAIRS_SEED + len(cases), S, name, "double",
                                   (("backlash", a.name, mb), ("coulomb_friction", a.joint, mf)), ()))
    return cases


def servo_cases() -> list[Case]:
    """The servo list (seeds 3700 and up, split ``servo``), a fifth tuning list made on
    2026-11-28 when a backlash in front of an integrating servo was first modelled: on every
    ``intvelocity`` actuator, its backlash alone at each of the three magnitudes, the backlash and
    a Coulomb friction on its joint (magnitudes 1 + 2 and 2 + 1), twice each by other designs,
    and two parameter-only cases (a false band must not appear). Deterministic."""
    S = systems()
    cases: list[Case] = []
    for name, sysm in S.items():
        app = set(applicable(sysm))
        for a in sysm.actuators:
            if a.kind != "intvelocity" or ("backlash", a.name) not in app:
                continue
            for _ in range(2):
                for mb in range(3):
                    cases.append(_case(SERVO_SEED + len(cases), S, name, "single", (("backlash", a.name, mb),), ()))
                if ("coulomb_friction", a.joint) in app:
                    for mb, mf in ((1, 2), (2, 1)):
                        cases.append(_case(SERVO_SEED + len(cases), S, name, "double",
                                           (("backlash", a.name, mb), ("coulomb_friction", a.joint, mf)), ()))
            for f in (0.8, 1.25):
                cases.append(_case(SERVO_SEED + len(cases), S, name, "none", (), (("mass", sysm.links[0].name, f),)))
    return cases


def beside_cases() -> list[Case]:
    """The beside list (seeds 3800 and up, split ``beside``), a sixth tuning list made on
    2026-11-29 after the fresh test list's fourth look named a false backlash beside a right
    motor lag, saturation or sensor offset in three cases: on every actuator, its motor lag and
    its saturation, and a sensor offset on its joint, one case each at a magnitude and design of
    its own (a band must not appear beside them). Deterministic."""
    S = systems()
    rng = np.random.default_rng(20261129)
    cases: list[Case] = []
    for name, sysm in S.items():
        app = set(applicable(sysm))
        for a in sysm.actuators:
            for e, t in (("motor_lag", a.name), ("actuator_saturation", a.name), ("sensor_offset", a.joint)):
                if (e, t) in app:
                    cases.append(_case(BESIDE_SEED + len(cases), S, name, "single", ((e, t, int(rng.integers(3))),), ()))
    return cases


def timing_cases() -> list[Case]:
    """The timing list (seeds 3900 and up, split ``timing``), a seventh tuning list made on
    2026-11-29 after the fresh test list's sixth look named a motor lag for a true action delay
    (twice, once at 5857 times the sensor's precision) and a delay beside a right lag: on every
    system, its action delay at each of the three magnitudes, each by a design of its own (a lag
    must not be named for it). Deterministic."""
    S = systems()
    cases: list[Case] = []
    for name, sysm in S.items():
        if ("action_delay", "") in applicable(sysm):
            for mag in range(3):
                cases.append(_case(TIMING_SEED + len(cases), S, name, "single", (("action_delay", "", mag),), ()))
    return cases


# the pairs of kinds ``build_cases`` draws its two-effect cases from
COMBOS = (("coulomb_friction", "action_delay"), ("mass_offset", "motor_lag"), ("coulomb_friction", "mass_offset"),
          ("action_delay", "actuator_saturation"), ("joint_stiffness", "sensor_offset"),
          ("coulomb_friction", "coulomb_friction"), ("viscous_damping", "motor_lag"),
          ("backlash", "coulomb_friction"))


def combos_cases() -> list[Case]:
    """The combos list (seeds 6000 and up, split ``combos``), an eighth tuning list made on
    2026-11-29 after the fresh test list's sixth look named both effects in 15 of its 24 pairs:
    on every system, every pair of kinds the lists draw two-effect cases from but a backlash and a
    friction (the pairs list has those), its targets drawn at random among the system's, once at
    magnitudes 1 + 2 and once at 2 + 1, each by a design of its own. Deterministic."""
    S = systems()
    rng = np.random.default_rng(20261130)
    cases: list[Case] = []
    for name, sysm in S.items():
        kinds: dict[str, list[str]] = {}
        for e, t in applicable(sysm):
            kinds.setdefault(e, []).append(t)
        for a, b in COMBOS:
            if "backlash" in (a, b) or a not in kinds or b not in kinds or (a == b and len(kinds[a]) < 2):
                continue
            for ma, mb in ((1, 2), (2, 1)):
                if a == b:
                    ta, tb = (str(x) for x in rng.choice(kinds[a], 2, replace=False))
                else:
                    ta, tb = str(rng.choice(kinds[a])), str(rng.choice(kinds[b]))
                cases.append(_case(COMBOS_SEED + len(cases), S, name, "double", ((a, ta, ma), (b, tb, mb)), ()))
    return cases


def pd_cases() -> list[Case]:
    """The PD-loop timing list (seeds 7000 and up, split ``pd``), a ninth tuning list made on
    2026-12-02 after the fresh list's oracle check found a 3-link arm's action delay under a PD
    loop named as a motor lag where the true delay predicts the validation segments 7 times better
    (no tuning list had a delay under a PD loop on an arm): on every system with a PD loop, its
    action delay and a motor lag (on an actuator drawn at random) at each of the three
    magnitudes, each by a design of its own with the excitation set to the PD loop. Deterministic."""
    S = systems()
    rng = np.random.default_rng(20261202)
    cases: list[Case] = []
    for name, sysm in S.items():
        if sysm.pd is None:
            continue
        for e in ("action_delay", "motor_lag"):
            for mag in range(3):
                t = "" if e == "action_delay" else str(rng.choice([a.name for a in sysm.actuators]))
                c = _case(PD_SEED + len(cases), S, name, "single", ((e, t, mag),), ())
                cases.append(dataclasses.replace(c, design=dataclasses.replace(c.design, excitation="pd")))
    return cases


SPLITS = ("tuning", "test", "extra", "focus", "pairs", "servo", "beside", "timing", "combos", "pd", "fresh")
"""Every list's name (the benchmarks' ``split=`` choices; a new list is added here and in ``split_cases``)."""


def split_cases(split: str) -> list[Case]:
    """The cases of one list by its name (``tuning``, ``test``, ``extra``, ``focus``, ``pairs``,
    ``servo``, ``beside``, ``timing``, ``combos``, ``pd``, ``fresh``; ``all``: the first list, both halves)."""
    made = {"focus": focus_cases, "pairs": pair_cases, "servo": servo_cases, "beside": beside_cases,
            "timing": timing_cases, "combos": combos_cases, "pd": pd_cases,
            "extra": lambda: build_cases(extra=True), "fresh": lambda: build_cases(fresh=True)}
    cases = made.get(split, build_cases)()
    return [c for c in cases if split == "all" or c.split == split]


# ------------------------------------------------------------------------------------------------
# simulation of the truth
MAGNITUDES = {  # relative levels 0, 1, 2 of each effect (scaled per system in ``_truth``)
    "coulomb_friction": (0.05, 0.1, 0.2),        # x the joint's RMS generalised force
    "viscous_damping": (0.1, 0.2, 0.4),          # force at RMS speed, x RMS force
    "joint_stiffness": (0.15, 0.3, 0.6),         # force at half the range, x RMS force
    "sensor_offset": (0.02, 0.05, 0.1),          # rad; slides: x the travel
    "mass_offset": (0.2, 0.4, 0.8),              # x the link's mass, at its tip
    "action_delay": (0.0037, 0.0083, 0.0165),    # s (not whole samples at any rate used)
    "motor_lag": (0.012, 0.025, 0.045),          # s
    "actuator_saturation": (0.75, 0.55, 0.35),   # x the 99th percentile of |actuator force|
    "backlash": (0.008, 0.016, 0.03),            # rad; slides: x 0.01 m
}


@dataclasses.dataclass
class Truth:
    mods: Mods
    delay: float = 0.0          # s
    lag: dict = dataclasses.field(default_factory=dict)       # actuator -> tau (s)
    offset: dict = dataclasses.field(default_factory=dict)    # joint -> sensor offset
    backlash: dict = dataclasses.field(default_factory=dict)  # joint -> dead-band width
    coupling: dict = dataclasses.field(default_factory=dict)  # joint -> (mesh stiffness, mesh damping)
    values: dict = dataclasses.field(default_factory=dict)    # what the diagnosis should find, by effect@target


def _scales(system: System, nominal_xml: str, ctrl: np.ndarray, h: float, n: int, q0) -> dict:
    """Per joint RMS generalised force, RMS speed and range; per actuator P99 |force|; from the
    nominal plant under the recorded excitation (open loop) or the PD loop."""
    m = mujoco.MjModel.from_xml_string(nominal_xml)
    m.opt.timestep = h
    d = mujoco.MjData(m)
    d.qpos[:] = q0
    frc, vel, pos, act = [], [], [], []
    for k in range(len(ctrl)):
        d.ctrl[:] = ctrl[k]
        for _ in range(n):
            mujoco.mj_step(m, d)
        frc.append(d.qfrc_actuator + d.qfrc_bias - d.qfrc_passive)
        vel.append(d.qvel.copy())
        pos.append(d.qpos.copy())
        act.append(d.actuator_force.copy())
    frc, vel, pos, act = map(np.asarray, (frc, vel, pos, act))
    return {"force": np.sqrt(np.mean(frc**2, 0)), "speed": np.sqrt(np.mean(vel**2, 0)),
            "range": np.ptp(pos, 0), "act99": np.percentile(np.abs(act), 99, axis=0)}


def _truth(case: Case, system: System, sc: dict) -> Truth:
    joints = [lk.joint for lk in system.links]
    links = {lk.name: lk for lk in system.links}
    acts = {a.name: a for a in system.actuators}
    tr = Truth(Mods())
    for kind, target, factor in case.nominal:
        if kind == "mass":
            tr.mods.mass_scale[target] = factor
        else:
            tr.mods.damping_scale[target] = factor
    for effect, target, level in case.effects:
        mag = MAGNITUDES[effect][level]
        if effect in ("coulomb_friction", "viscous_damping", "joint_stiffness", "sensor_offset"):
            j = joints.index(target)
            slide = system.links[j].jtype == "slide"
            F = max(float(sc["force"][j]), 1e-6)
            if effect == "coulomb_friction":
                tr.mods.frictionloss[target] = mag * F
                tr.values[f"{effect}@{target}"] = {f"coulomb:{target}": mag * F}
            elif effect == "viscous_damping":
                c = mag * F / max(float(sc["speed"][j]), 1e-6)
                tr.mods.extra_damping[target] = c
                tr.values[f"{effect}@{target}"] = {f"viscous:{target}": c}
            elif effect == "joint_stiffness":
                k = mag * F / max(0.5 * float(sc["range"][j]), 1e-6)
                tr.mods.stiffness[target] = k
                tr.values[f"{effect}@{target}"] = {f"stiffness:{target}": k}
            else:
                off = mag * (max(float(sc["range"][j]), 1e-3) if slide else 1.0)
                tr.offset[target] = off
                tr.values[f"{effect}@{target}"] = {f"sensor_offset:{target}": off}
        elif effect == "mass_offset":
            lk = links[target]
            mp = mag * lk.mass
            tr.mods.payload[target] = (mp, lk.tip)
            tr.values[f"{effect}@{target}"] = {f"payload:{target}": mp}
        elif effect == "action_delay":
            tr.delay = mag
            tr.values[effect] = {"action_delay_seconds": mag}
        elif effect == "motor_lag":
            tr.lag[target] = mag
            tr.values[f"{effect}@{target}"] = {f"motor_lag:{target}": mag}
        elif effect == "actuator_saturation":
            a = list(acts).index(target)
            lim = mag * max(float(sc["act99"][a]), 1e-6)
            tr.mods.forcerange[target] = lim
            tr.values[f"{effect}@{target}"] = {f"saturation:{target}": lim}
        elif effect == "backlash":
            a = acts[target]
            lk = next(x for x in system.links if x.joint == a.joint)
            width = mag * (0.01 if lk.jtype == "slide" else 1.0)
            # the motor side: a light rotor meshing with the link through the dead band; the mesh
            # is 30x stiffer than the link's own 5 Hz mode or the servo, the rotor's mesh mode
            # stays below 2000 rad/s (stable at the truth's 0.25 ms step)
            J = _joint_inertia(system, lk)
            servo = a.kp * a.gear**2 if a.kind in ("position", "intvelocity") else 0.0
            k_c = 30.0 * max(J * (2 * np.pi * 5.0) ** 2, servo)
            J_r = max(0.05 * J, k_c / 2000.0**2)
            tr.mods.rotor[a.joint] = J_r
            tr.coupling[a.joint] = (k_c, 2 * 0.5 * math.sqrt(k_c * J_r))
            tr.backlash[a.joint] = width
            tr.values[f"{effect}@{target}"] = {f"backlash:{target}": width}
    return tr


def _joint_inertia(system: System, lk: Link) -> float:
    if lk.jtype == "slide":
        return lk.mass
    pos, quat, inertia = _link_inertial(system, lk)
    return float(np.max(inertia) + lk.mass * np.dot(pos, pos))


def _excitation(system: System, design: Design, T: int, dt: float, rng, amp: float = 1.0) -> np.ndarray:
    """Open-loop commands ``[T, nu]`` (servos: references), or references for the PD loop;
    ``amp`` scales the open-loop commands about the middle of the ctrl range."""
    t = np.arange(T) * dt
    u = np.zeros((T, len(system.actuators)))
    kind = design.excitation
    for i, a in enumerate(system.actuators):
        lo, hi = a.ctrlrange
        mid, half = (lo + hi) / 2, (hi - lo) / 2
        if kind in ("multisine", "pd"):
            sig = np.zeros(T)
            for f in rng.uniform(0.1, 2.5, size=6):
                sig += np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
            sig /= np.abs(sig).max() + 1e-12
        elif kind == "chirp":
            f0, f1 = 0.1, rng.uniform(2.0, 5.0)
            sig = np.sin(2 * np.pi * (f0 * t + 0.5 * (f1 - f0) * t**2 / max(t[-1], 1e-9)))
        elif kind == "prbs":
            hold = max(1, int(rng.uniform(0.05, 0.25) / dt))
            sig = np.repeat(rng.choice([-1.0, 1.0], size=T // hold + 1), hold)[:T]
        else:  # random steps
            sig = np.zeros(T)
            k = 0
            while k < T:
                n = max(1, int(rng.uniform(0.2, 1.0) / dt))
                sig[k:k + n] = rng.uniform(-1, 1)
                k += n
        if kind == "pd":  # a reference trajectory in joint units for the generator's own loop
            u[:, i] = 0.5 * sig * (1.0 if _joint(system, a).jtype == "hinge" else 0.05)
        else:
            u[:, i] = np.clip(mid + 0.8 * amp * half * sig, lo, hi)
    return u


def _open_loop_amplitude(system: System, design: Design, nominal_xml: str, T: int, dt: float, seed: int,
                         h: float, n: int, q0) -> float:
    """The largest of 1, 1/2, 1/4, ... at which the nominal plant's open-loop motion stays within
    the system's range (4 rad per hinge, 0.5 m per slide): arms swing and sliders drift, as in lab
    data, but nothing whirls through dozens of turns."""
    if design.excitation == "pd":
        return 1.0
    m = mujoco.MjModel.from_xml_string(nominal_xml)
    m.opt.timestep = h
    limit = np.array([system.max_range or (4.0 if lk.jtype == "hinge" else 0.5) for lk in system.links])
    amp = 1.0
    for _ in range(8):
        u = _excitation(system, design, T, dt, np.random.default_rng(seed), amp)
        d = mujoco.MjData(m)
        d.qpos[:] = q0
        lo, hi = np.array(q0, float), np.array(q0, float)
        ok = True
        for k in range(T):
            d.ctrl[:] = u[k]
            for _ in range(n):
                mujoco.mj_step(m, d)
            lo, hi = np.minimum(lo, d.qpos), np.maximum(hi, d.qpos)
            if np.any(hi - lo > limit) or not np.all(np.isfinite(d.qpos)):
                ok = False
                break
        if ok:
            return amp
        amp *= 0.5
    return amp


def _joint(system: System, a: Actuator) -> Link:
    return next(lk for lk in system.links if lk.joint == a.joint)


def simulate(system: System, design: Design, truth: Truth, truth_xml: str, ctrl_or_ref: np.ndarray,
             q0: np.ndarray, rng, h: float, n: int, v0: np.ndarray | None = None,
             act0: np.ndarray | None = None, meas0: np.ndarray | None = None,
             rotor0: np.ndarray | None = None) -> dict:
    """Step the truth with ``mj_step`` and log at ``design.rate``; effects applied here.

    The command logged at sample k is the one sent at t_k (held until t_k+1): the open-loop
    excitation, or the PD loop's output computed from the *logged* (noisy, offset) positions.
    ``v0``, ``act0``, ``meas0``, ``rotor0`` (optional): the joints' start velocities, the
    actuators' activations, the PD loop's previous measurement and the backlash rotors' positions
    and velocities ``[2, nrotors]``, to start mid-recording (``visibility``). Returns the logged
    ``qpos``, ``qvel``, ``ctrl``, ``force`` ``[T, ...]``, and the plant's own ``q_true``, ``v_true``
    ``[T, njoints]``, ``act`` ``[T, na]`` and ``rotor`` ``[T, 2, nrotors]`` at each sample.
    """
    m = mujoco.MjModel.from_xml_string(truth_xml)
    m.opt.timestep = h
    d = mujoco.MjData(m)
    jn = [lk.joint for lk in system.links]
    qadr = [m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j)] for j in jn]
    dadr = [m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j)] for j in jn]
    rot = {j: (m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j + "_rotor")],
               m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j + "_rotor")])
           for j in truth.backlash}
    for k, a in enumerate(qadr):
        d.qpos[a] = q0[k]
        if v0 is not None:
            d.qvel[dadr[k]] = v0[k]
    for r, (j, (qa, da)) in enumerate(rot.items()):
        d.qpos[qa] = d.qpos[qadr[jn.index(j)]] if rotor0 is None else rotor0[0, r]
        d.qvel[da] = d.qvel[dadr[jn.index(j)]] if rotor0 is None else rotor0[1, r]
    for i, a in enumerate(system.actuators):  # integrating servos start at the joint's position
        if a.kind == "intvelocity":
            d.act[m.actuator_actadr[i]] = d.qpos[qadr[jn.index(a.joint)]]
    if act0 is not None and m.na:
        d.act[:] = act0
    dt = 1.0 / design.rate
    T = len(ctrl_or_ref)
    nu = len(system.actuators)
    dt_h = dt / n
    lag_state = None
    sent = np.zeros((T, nu))
    log_q = np.zeros((T, len(jn)))
    log_v = np.zeros((T, len(jn)))
    log_force = np.zeros((T, nu))
    log_true = np.zeros((T, 2, len(jn)))
    log_act = np.zeros((T, m.na))
    log_rot = np.zeros((T, 2, len(rot)))
    prev_meas = None if meas0 is None else np.asarray(meas0, float)
    for k in range(T):
        q_true = np.array([d.qpos[a] for a in qadr])
        v_true = np.array([d.qvel[a] for a in dadr])
        log_true[k] = q_true, v_true
        log_act[k] = d.act
        log_rot[k] = [[d.qpos[qa] for qa, _ in rot.values()], [d.qvel[da] for _, da in rot.values()]]
        meas = q_true + np.array([truth.offset.get(j, 0.0) for j in jn])
        if design.quant > 0:
            meas = np.round(meas / design.quant) * design.quant
        meas = meas + design.noise * rng.standard_normal(len(jn))
        log_q[k] = meas
        log_v[k] = v_true + 10 * design.noise * rng.standard_normal(len(jn)) + (
            design.quant / dt * 0.3 * rng.standard_normal(len(jn)) if design.quant else 0.0)
        if design.excitation == "pd":
            vel = (meas - prev_meas) / dt if prev_meas is not None else np.zeros_like(meas)
            for i, a in enumerate(system.actuators):
                jj = jn.index(a.joint)
                kp, kd = system.pd[i]
                torque = kp * (ctrl_or_ref[k, i] - meas[jj]) - kd * vel[jj]
                per_ctrl = a.gear if a.kind == "motor" else (a.gain if a.kind == "general" else 1.0)
                sent[k, i] = np.clip(torque / per_ctrl, *a.ctrlrange)
        else:
            sent[k] = ctrl_or_ref[k]
        prev_meas = meas
        if lag_state is None:
            lag_state = sent[0].copy()
        for s in range(n):
            t_now = (k * n + s) * dt_h
            # delay line at the physics rate: the command sent at t - D is applied at t
            kd_ = int(math.floor((t_now - truth.delay) / dt + 1e-9))
            u = sent[max(kd_, 0)] if truth.delay > 0 else sent[k]
            # first-order lag at the physics rate (forward Euler, as a drive's current loop runs)
            for i, a in enumerate(system.actuators):
                tau = truth.lag.get(a.name, 0.0)
                if tau > 0:
                    lag_state[i] += (dt_h / tau) * (u[i] - lag_state[i])
                    u = u.copy()
                    u[i] = lag_state[i]
            d.ctrl[:] = u
            d.qfrc_applied[:] = 0.0
            for j, (qa, da) in rot.items():
                jj = jn.index(j)
                delta = d.qpos[qa] - d.qpos[qadr[jj]]
                half = 0.5 * truth.backlash[j]
                k_c, c_c = truth.coupling[j]
                engaged = abs(delta) > half
                tq = k_c * np.sign(delta) * max(abs(delta) - half, 0.0) + (
                    c_c * (d.qvel[da] - d.qvel[dadr[jj]]) if engaged else 0.0)
                d.qfrc_applied[dadr[jj]] += tq
                d.qfrc_applied[da] -= tq
            mujoco.mj_step(m, d)
            if not np.all(np.isfinite(d.qpos)):
                raise RuntimeError("the true plant diverged")
        log_force[k] = d.actuator_force[:nu]
    return {"qpos": log_q, "qvel": log_v, "ctrl": sent, "force": log_force, "q_true_end": q_true,
            "q_true": log_true[:, 0], "v_true": log_true[:, 1], "act": log_act, "rotor": log_rot}


def _q0(system: System, rng) -> np.ndarray:
    q = []
    for lk in system.links:
        q.append(rng.uniform(-0.3, 0.3) if lk.jtype == "hinge" else rng.uniform(-0.02, 0.02))
    return np.array(q)


def physics_step(design: Design) -> tuple[float, int]:
    """The truth's physics step: reality is continuous, so the truth runs at <= 0.25 ms (converged
    for these plants: halving it changes recordings by less than the sensor noise), a whole
    fraction of the log period. (The first version ran at <= 1 ms, whose own discretisation error
    on the stiff servos exceeded the sensor noise: the truth was then a numerical artefact.)"""
    dt = 1.0 / design.rate
    h_max = min(design.timestep, 0.00025)
    n = int(math.ceil(dt / h_max - 1e-9))
    return dt / n, n


def _setup(case: Case) -> tuple:
    """What a case's recordings are made from: ``(system, nominal_xml, h, n, T, q0s, excs, amp,
    sc, rng)``, ``rng`` left where the recordings' own draws start (``generate``)."""
    system = systems()[case.system]
    design = case.design
    rng = np.random.default_rng(case.seed)
    nominal_xml = write_mjcf(system, design.integrator, design.timestep, design.mass_mode,
                             model_name=f"{case.system}_nominal")
    h, n = physics_step(design)
    dt = 1.0 / design.rate
    T = int(round(design.seconds / dt))
    q0s = [_q0(system, rng) for _ in range(3)]
    seeds = [int(x) for x in rng.integers(0, 2**31, size=3)]
    amp = _open_loop_amplitude(system, design, nominal_xml, T, dt, seeds[0], h, n, q0s[0])
    excs = [_excitation(system, design, T, dt, np.random.default_rng(sd), amp) for sd in seeds]
    sc_ctrl = excs[0] if design.excitation != "pd" else np.zeros_like(excs[0])
    if design.excitation == "pd":  # scales from an open-loop multisine of the same system
        sc_ctrl = _excitation(system, dataclasses.replace(design, excitation="multisine"), T, dt,
                              np.random.default_rng(case.seed + 7))
    sc = _scales(system, nominal_xml, sc_ctrl, h, n, q0s[0])
    return system, nominal_xml, h, n, T, q0s, excs, amp, sc, rng


def generate(case: Case, folder: str) -> dict:
    """Write the case into ``folder``; returns its description (also ``truth.json``)."""
    design = case.design
    os.makedirs(folder, exist_ok=True)
    system, nominal_xml, h, n, T, q0s, excs, amp, sc, rng = _setup(case)
    dt = 1.0 / design.rate
    truth = _truth(case, system, sc)
    truth_xml = write_mjcf(system, design.integrator, design.timestep, design.mass_mode, truth.mods,
                           model_name=f"{case.system}_truth")
    with open(os.path.join(folder, "nominal.xml"), "w") as f:
        f.write(nominal_xml)
    t0 = float(rng.uniform(0, 1000))  # logger clocks do not start at 0
    files = []
    for r, name in enumerate(["train_0", "train_1", "heldout"]):
        out = simulate(system, design, truth, truth_xml, excs[r], q0s[r], rng, h, n)
        cols = {"time": t0 + np.arange(T) * dt}
        for k, lk in enumerate(system.links):
            cols[f"qpos:{lk.joint}"] = out["qpos"][:, k]
        if design.qvel:
            for k, lk in enumerate(system.links):
                cols[f"qvel:{lk.joint}"] = out["qvel"][:, k]
        for i, a in enumerate(system.actuators):
            cols[f"ctrl:{a.name}"] = out["ctrl"][:, i]
        path = os.path.join(folder, f"{name}.csv")
        _write_csv(path, cols)
        files.append(path)
    desc = {"case": case.label, "generator_version": GENERATOR_VERSION, "seed": case.seed, "split": case.split, "system": case.system, "kind": case.kind,
            "effects": [list(e) for e in case.effects], "nominal": [list(x) for x in case.nominal],
            "design": dataclasses.asdict(design), "truth_values": truth.values, "open_loop_amplitude": amp,
            "truth_physics_step": h, "files": [os.path.basename(p) for p in files]}
    with open(os.path.join(folder, "truth.json"), "w") as f:
        json.dump(desc, f, indent=1)
    return desc


def visibility(case: Case, seconds: float = 1.0) -> float:
    """How far the hidden effects move the measured positions over ``seconds`` from a known state,
    in units of the measurement's precision (sqrt(noise^2 + step^2 / 12)): each recording, noise-free,
    is cut into segments; each segment of the true plant is set against the plant without one
    hidden effect (the other kept; a backlash's band closed, its rotor and mesh kept), started at
    its true state (positions, velocities, activations, rotors) and sent the same commands (the
    PD loop closed on its own measurement). The RMS difference over every segment, at the joint
    where it is largest; of two effects, the less visible one's. A parameter-only case: 0.

    Below a few units the hidden physics moves a prediction about as much as the sensor's own
    noise does over one diagnosis horizon: the data can show it only through many segments'
    averages, if at all."""
    if not case.effects:
        return 0.0
    design = case.design
    system, _, h, n, T, q0s, excs, _, sc, _ = _setup(case)
    clean = dataclasses.replace(design, noise=0.0, quant=0.0)
    truth = _truth(case, system, sc)

    def xml(tr, name):
        return write_mjcf(system, design.integrator, design.timestep, design.mass_mode, tr.mods,
                          model_name=f"{case.system}_{name}")

    txml = xml(truth, "truth")
    K = max(2, int(round(seconds * design.rate)))
    quiet = np.random.default_rng(0)  # (noise-free: its draws are multiplied by 0)
    runs = [simulate(system, clean, truth, txml, excs[r], q0s[r], quiet, h, n) for r in range(3)]
    out = []
    for e in case.effects:
        base = _truth(dataclasses.replace(case, effects=tuple(x for x in case.effects if x != e)), system, sc)
        if e[0] == "backlash":  # the band closed, its rotor and mesh kept: what shows is the band
            joint = next(a.joint for a in system.actuators if a.name == e[1])
            base.mods.rotor[joint], base.coupling[joint] = truth.mods.rotor[joint], truth.coupling[joint]
            base.backlash[joint] = 0.0
        bxml = xml(base, "base")
        same_rotors = list(base.backlash) == list(truth.backlash)
        sq, count = np.zeros(len(system.links)), 0
        for r, a in enumerate(runs):
            for k0 in range(0, T - K + 1, K):
                b = simulate(system, clean, base, bxml, excs[r][k0:k0 + K], a["q_true"][k0], quiet, h, n,
                             v0=a["v_true"][k0], act0=a["act"][k0], meas0=a["qpos"][k0 - 1] if k0 else None,
                             rotor0=a["rotor"][k0] if same_rotors else None)
                sq += np.sum((a["qpos"][k0:k0 + K] - b["qpos"]) ** 2, 0)
                count += K
        out.append(float(np.max(np.sqrt(sq / count))))
    return min(out) / math.sqrt(design.noise ** 2 + design.quant ** 2 / 12)


def _write_csv(path: str, cols: dict) -> None:
    names = list(cols)
    data = np.column_stack([cols[c] for c in names])
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.10g")


def fingerprint(cases: list[Case]) -> str:
    """A hash of the case list, to show the frozen list did not change."""
    text = json.dumps([dataclasses.asdict(c) for c in cases], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]
