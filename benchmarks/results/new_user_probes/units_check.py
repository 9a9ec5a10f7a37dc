"""The units hint (``sim2real/sysid/units.py``) on the independent benchmark's tuning lists: each case's
training recordings as logged (in the model's units: a hint is a false one), then with every
hinge's angle written in degrees and every slide's position in millimetres, the servos' setpoints
with them (a hint is wanted, where the data can tell). Run on every case, not only where the kept
model leaves motion unexplained (where the diagnosis asks): a stricter test of false hints.
Prints one line per case and the counts.

    PYTHONPATH=. python benchmarks/results/new_user_probes/units_check.py tuning [WORK]
    PYTHONPATH=. python benchmarks/results/new_user_probes/units_check.py extra [WORK]
"""
import os
import sys

import mujoco
import numpy as np

sys.path.insert(0, "benchmarks")
import diagnosis_independent as di  # noqa: E402
import sysid_cases  # noqa: E402

from sim2real.sysid.recordings import Recording, load_all  # noqa: E402
from sim2real.sysid.system import System  # noqa: E402
from sim2real.sysid.trajectory import from_recording  # noqa: E402
from sim2real.sysid.units import OTHER, _servos, logged_units  # noqa: E402


def relogged(recs, m):
    """``recs`` with every hinge in degrees, every slide in mm, and the servos' commands with them."""
    joint = {m.joint(j).name: OTHER[int(m.jnt_type[j])][0] for j in range(m.njnt) if int(m.jnt_type[j]) in OTHER}
    servo = {m.actuator(a).name: OTHER[int(m.jnt_type[m.actuator_trnid[a, 0]])][0]
             for a in _servos(m, list(range(m.njnt)))}
    out = []
    for r in recs:
        cols = dict(r.columns)
        for k in cols:
            kind, name = k.split(":", 1)
            s = joint.get(name) if kind in ("qpos", "qvel") else servo.get(name) if kind == "ctrl" else None
            if s:
                cols[k] = cols[k] / s
        out.append(Recording(r.path, r.time, cols))
    return out


def main(split, work):
    false = hits = total = 0
    for case in sysid_cases.split_cases(split):
        folder = os.path.join(work, case.label)
        di.case_files(case, folder)
        model = os.path.join(folder, "nominal.xml")
        m = mujoco.MjModel.from_xml_path(model)
        recs = load_all([os.path.join(folder, f"train_{i}.csv") for i in (0, 1)], m)
        system = System(model, dt=recs[0].dt)
        z0 = np.array(system.spec.default, float)
        H = max(10, int(round(0.1 / recs[0].dt)))  # 0.1 s predictions
        as_logged = logged_units(system, z0, [from_recording(r, system) for r in recs], H)
        converted = logged_units(system, z0, [from_recording(r, system) for r in relogged(recs, m)], H)
        total, false, hits = total + 1, false + bool(as_logged), hits + bool(converted)
        print(f"{case.label} | as logged: {as_logged[80:] or '-'} | converted: {converted[80:] or 'no hint'}", flush=True)
    print(f"{split}: {total} cases; a hint as logged (false) {false}; a hint in degrees and mm {hits}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else "/tmp/units_check")
