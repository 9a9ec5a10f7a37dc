"""The library of candidate missing-physics effects the diagnosis searches.

Each candidate is an effect of the simulator's effects library attached to one joint, actuator
or body (or global), described by the physics parameters it sets. ``none`` re-fits only the
nominal parameters (masses, declared damping, gains). Parameters enter the inverse-dynamics
residual linearly (fitted in closed form with bounds) or through one nonlinear parameter that
is searched on a grid with the linear ones re-fitted at every grid point.

=====================  ==========  ==========================================================
effect                 attached    parameters (spec names)
=====================  ==========  ==========================================================
none                   --          nominal only
coulomb_friction       joint       ``coulomb`` (+ ``coulomb_asym``: different level each way)
viscous_damping        joint       ``viscous`` (only where the MJCF declares no damping)
joint_stiffness        joint       ``stiffness`` (only where the MJCF declares no spring)
sensor_offset          joint       ``sensor_offset`` (grid, symmetric)
mass_offset            body        ``payload`` (bodies with a ``payload_<body>`` site off the COM)
action_delay           global      ``action_delay`` (grid, fractional control steps)
motor_lag              actuator    ``motor_lag`` (grid, time constant)
actuator_saturation    actuator    ``saturation`` (grid, force limit)
backlash               actuator    ``backlash`` (grid, dead-band width)
=====================  ==========  ==========================================================
"""
from __future__ import annotations

import dataclasses

import numpy as np

from sim2real.sysid.system import System

EFFECTS = ("none", "coulomb_friction", "viscous_damping", "joint_stiffness", "sensor_offset", "mass_offset",
           "action_delay", "motor_lag", "actuator_saturation", "backlash")


@dataclasses.dataclass(frozen=True)
class Candidate:
    """One hypothesis: ``effect`` at ``target``.

    Attributes:
      effect: a name from ``EFFECTS``.
      target: joint, actuator or body name ('' for global / none).
      linear: spec parameters fitted linearly (besides the nominal ones).
      grid_param: spec parameter searched on ``grid`` (None for purely linear candidates).
      grid: values tried for ``grid_param``.
      two_sided: Coulomb friction with separate levels for each direction of motion.
    """

    effect: str
    target: str = ""
    linear: tuple[str, ...] = ()
    grid_param: str | None = None
    grid: tuple[float, ...] = ()
    two_sided: bool = False

    @property
    def label(self) -> str:
        return self.effect if not self.target else f"{self.effect}@{self.target}"

    @property
    def num_params(self) -> int:
        return len(self.linear) + (1 if self.grid_param else 0) + (2 if self.effect == "coulomb_friction" else 0)


def library(system: System, dt: float, q_range: np.ndarray, force_scale: np.ndarray,
            effects: tuple[str, ...] = EFFECTS) -> list[Candidate]:
    """All candidates for this model.

    Args:
      dt: sample period of the recordings (delay / lag grids are in samples).
      q_range: ``[njnt]`` position range covered by the data (backlash grid).
      force_scale: ``[nu]`` typical actuator force magnitude (saturation grid: its quantiles).
    """
    unknown = set(effects) - set(EFFECTS)
    if unknown:
        raise ValueError(f"unknown effect(s) {sorted(unknown)}; the library has {', '.join(EFFECTS)}")
    m = system.mj
    out = [Candidate("none")] if "none" in effects else []
    act_joints = {int(m.actuator_trnid[a, 0]) for a in range(m.nu)}
    for j, jn in enumerate(system.joints):
        if "coulomb_friction" in effects:
            out.append(Candidate("coulomb_friction", jn))
            out.append(Candidate("coulomb_friction", jn, two_sided=True))
        if "viscous_damping" in effects and not system.declared_damping(jn):
            out.append(Candidate("viscous_damping", jn, (f"viscous:{jn}",)))
        if "joint_stiffness" in effects and not system.declared_stiffness(jn):
            out.append(Candidate("joint_stiffness", jn, (f"stiffness:{jn}",)))
        if "sensor_offset" in effects:
            # searched on a symmetric grid (+ a scalar search), not linearised at zero: behind a
            # force-limited servo the residual is flat in the offset until the offset is found
            # (the nominal model's servo force sits at its limit), so a Gauss-Newton step from
            # zero goes nowhere
            r = max(float(q_range[j]), 1e-6)
            mag = np.geomspace(2e-4 * r, 0.1 * r, 8)
            out.append(Candidate("sensor_offset", jn, grid_param=f"sensor_offset:{jn}",
                                 grid=tuple(np.concatenate([-mag[::-1], [0.0], mag]))))
    for bn in system.bodies:
        # a payload at the body's own centre of mass is the same hypothesis as a re-fitted body
        # mass (``none``): only bodies with a declared ``payload_<body>`` site elsewhere get one
        i = system.bodies.index(bn)
        if ("mass_offset" in effects and f"payload:{bn}" in system.spec and i in system.physics.payload_pos
                and np.linalg.norm(system.physics.payload_pos[i] - system.mj.body_ipos[i]) > 1e-6):
            out.append(Candidate("mass_offset", bn, (f"payload:{bn}",)))
    max_delay = system.spec["action_delay"].high
    if "action_delay" in effects:
        # timing effects are searched from one sample period up: a shorter delay or lag is
        # within the recording's timestamp convention (where in the sample period a command
        # took effect), and a sub-sample one improves predictions from noisy measured states
        # even of a plant that has none
        out.append(Candidate("action_delay", "", grid_param="action_delay",
                             grid=tuple(np.arange(1.0, max_delay + 1e-9, 0.5))))
    for a, an in enumerate(system.actuators):
        j = int(m.actuator_trnid[a, 0])
        if "motor_lag" in effects:
            out.append(Candidate("motor_lag", an, grid_param=f"motor_lag:{an}",
                                 grid=tuple(np.geomspace(dt, 40 * dt, 16))))
        if "actuator_saturation" in effects:
            s = float(force_scale[a])
            out.append(Candidate("actuator_saturation", an, grid_param=f"saturation:{an}",
                                 grid=tuple(np.geomspace(0.15 * s, 1.5 * s, 16))))
        if "backlash" in effects and j in act_joints:
            r = max(float(q_range[j]), 1e-6)
            out.append(Candidate("backlash", an, grid_param=f"backlash:{an}",
                                 grid=tuple(np.geomspace(2e-4 * r, 0.1 * r, 16))))
    return out
