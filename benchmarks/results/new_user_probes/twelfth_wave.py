"""A twelfth wave: recordings logged in other units or conventions than the model's, as loggers write them.

A hobby servo's or an encoder board's log gives degrees; a linear stage's controller, millimetres.
The model is in radians and metres (MuJoCo's units), and a new user may not think of it. Each probe
records a plant on native MuJoCo as the second wave does (3 recordings of 8 s at 200 Hz, position
noise 1e-3 in the model's units, 2 to train on, the third held out), then writes its positions (and
the setpoints of servos, which a controller in those units sends in them) in the logger's unit:

- the second wave's pendulum with a 0.08 N m hinge friction, its angle logged in degrees (and the
  same recordings in radians, for the answer the diagnosis gives there);
- the second wave's 2-link arm on filtered PD servos (``general``, filterexact) carrying a 0.15 kg
  payload at its tip, angles and setpoints in degrees;
- the second wave's slider on a force motor with a 0.8 N rail friction, its position in mm;
- the second wave's linear axis on a `position` servo behind a 12 ms command delay, position and
  setpoints in mm (its joint has a range, and the recordings' positions lie beyond it), and the
  same with the range left out of the model: a servo on a joint that gravity does not load is the
  same system in any unit (its forces all scale with it), so the data cannot say which unit it
  was logged in;
- an encoder that counts the other way (wired or mounted reversed): the pendulum's angle, and the
  second wave's gravity-compensated 2-link arm's elbow (a 0.15 N m s/rad damping at the shoulder);
- the pendulum's angle counted from upright (the model's zero hangs);
- the pendulum's motor force logged beside it (`force:m`): its torque in N m, and its current in A
  (a torque constant of 0.08 N m/A: 12.5x the torque).

Prints the probes' table and, per probe, the first note on units (the hint of ``sysid/units.py``, or a
command column far past its ``ctrlrange``, ``recordings._commands_past_range``) and how many there were.
``PYTHONPATH=. python benchmarks/results/new_user_probes/twelfth_wave.py [WORK] [PROBE ...]``.
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probes import diagnose_and_print  # noqa: E402
from second_wave import AXIS, GRAVCOMP, PENDULUM, SERVO_ARM, SLIDER, record  # noqa: E402

DEG, MM = 180 / np.pi, 1000.0

# name: (model text, the truth for {truth}, words, drive, extras, {column prefix: scale})
PROBES = {
    "pendulum_radians_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m (logged in "
                                  "radians)", "multisine", {}, {}),
    "pendulum_degrees_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m (the angle "
                                  "logged in degrees)", "multisine", {}, {"qpos:": DEG}),
    "servo_arm_degrees_payload": (SERVO_ARM, '<geom type="sphere" pos="0 0 -0.25" size="0.01" mass="0.15"/>',
                                  "mass_offset@lower 0.15 kg at its tip (angles and setpoints in degrees)", "steps", {},
                                  {"qpos:": DEG, "ctrl:": DEG}),
    "slider_mm_friction": (SLIDER, 'frictionloss="0.8"', "coulomb_friction@rail 0.8 N (the position logged in mm)",
                           "steps", {}, {"qpos:": MM}),
    "axis_mm_delay": (AXIS, "", "action_delay 0.012 s (position and setpoints in mm)", "steps", {"delay_s": 0.012},
                      {"qpos:": MM, "ctrl:": MM}),
    "axis_mm_delay_no_range": (AXIS.replace(' range="-0.5 0.5"', ""), "", "action_delay 0.012 s (position and "
                               "setpoints in mm; the model's joint without a range)", "steps", {"delay_s": 0.012},
                               {"qpos:": MM, "ctrl:": MM}),
    "pendulum_flipped_encoder_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m (the "
                                          "encoder counts the other way)", "multisine", {}, {"qpos:": -1.0}),
    "gravcomp_arm_flipped_elbow_damping": (GRAVCOMP, 'damping="0.15"', "viscous_damping@j1 0.15 N m s/rad (the "
                                           "elbow's encoder counts the other way)", "multisine", {},
                                           {"qpos:j2": -1.0}),
    "pendulum_upright_zero_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m (the angle "
                                       "counted from upright)", "multisine", {}, {"qpos:": (1.0, np.pi)}),
    "pendulum_torque_logged_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m (the motor's "
                                        "torque logged, in N m)", "multisine", {}, {"force:m": 1.0}),
    "pendulum_current_logged_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m (the "
                                         "motor's current logged as its force, A at 0.08 N m/A)", "multisine", {},
                                         {"force:m": 1 / 0.08}),
}


def relog(paths, scales):
    """Rewrite each recording's columns whose name starts with a key of ``scales`` multiplied by it
    (or, given ``(scale, offset)``, times the scale plus the offset);
    ``force:m``: add the motor's measured force, at each row the force of the command held until
    then (the previous row's; the motor is a gear-1 torque motor, its command clipped to +-2 N m),
    times the scale, with noise of 1% of the range."""
    rng = np.random.default_rng(7)
    for p in paths:
        header = open(p).readline().strip().split(",")
        data = np.loadtxt(p, delimiter=",", skiprows=1)
        if "force:m" in scales:
            u = np.clip(data[:, header.index("ctrl:m")], -2.0, 2.0)
            force = np.concatenate([[0.0], u[:-1]]) + rng.normal(0, 0.02, len(u))
            data = np.column_stack([data, force * scales["force:m"]])
            header = header + ["force:m"]
        for k, name in enumerate(header):
            for prefix, s in scales.items():
                if name.startswith(prefix) and prefix != "force:m":
                    s, c = s if isinstance(s, tuple) else (s, 0.0)   # (a scale and an offset)
                    data[:, k] = data[:, k] * s + c
        np.savetxt(p, data, delimiter=",", header=",".join(header), comments="")


def main(work, only=()):
    os.makedirs(work, exist_ok=True)
    print("| probe | truth | named | values | held-out NRMSE before -> after | seconds |")
    print("|---|---|---|---|---|---|")
    hints = {}
    for name, (text, truth, words, drive, extras, scales) in PROBES.items():
        if only and name not in only:
            continue
        nominal, paths = record(name, text, truth, drive, extras, work)
        relog(paths, scales)
        diagnose_and_print(name, words, nominal, paths, work)
        notes = os.path.join(work, name + "_notes.json")
        if os.path.exists(notes):
            said = [n for n in json.load(open(notes)) if "other units" in n]  # (the hint; commands past their range)
            hints[name] = f"{said[0]} ({len(said)} such notes)" if said else "no note on units"
    print()
    for name, hint in hints.items():
        print(f"- {name}: {hint}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_12", tuple(sys.argv[2:]))
