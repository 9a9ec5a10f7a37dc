"""The units hint (``sim2real/sysid/units.py``) on the independent benchmark's tuning lists: each case's
training recordings as logged (in the model's units: a hint is a false one), then with every
hinge's angle written in degrees and every slide's position in millimetres, the servos' setpoints
with them, then with the first joint's sign flipped (its servo's setpoint with it), then with the
first hinge's zero half a turn away (a hint is wanted, where the data can tell). Run on every case, not only where the kept model leaves motion
unexplained (where the diagnosis asks): a stricter test of false hints. Prints one line per case
and the counts.

    PYTHONPATH=. python benchmarks/results/new_user_probes/units_check.py tuning [WORK]
    PYTHONPATH=. python benchmarks/results/new_user_probes/units_check.py extra [WORK]
    PYTHONPATH=. python benchmarks/results/new_user_probes/units_check.py real   # the bundled real recordings

``real``: each bundled real dataset's first split (``benchmarks/real_datasets.py``), as logged, with
0.05 s, 0.1 s and 0.3 s predictions (a hint there is a false one).
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


def relogged(recs, m, reading, joints):
    """``recs`` with ``joints`` logged in ``OTHER``'s ``reading`` (degrees or mm, the sign flipped,
    the zero half a turn away), the servos' commands on them alike (a position's setpoint offset
    too)."""
    read = {m.joint(j).name: OTHER[int(m.jnt_type[j])][reading][:2] for j in joints}
    servo = {}
    for a in _servos(m, list(joints)):
        s, c = OTHER[int(m.jnt_type[m.actuator_trnid[a, 0]])][reading][:2]
        servo[m.actuator(a).name] = (s, c if m.actuator_biasprm[a, 1] != 0 else 0.0)
    out = []
    for r in recs:
        cols = dict(r.columns)
        for k in cols:
            kind, name = k.split(":", 1)
            if kind == "qpos" and name in read:
                cols[k] = (cols[k] - read[name][1]) / read[name][0]
            elif kind == "qvel" and name in read:
                cols[k] = cols[k] / read[name][0]
            elif kind == "ctrl" and name in servo:
                cols[k] = (cols[k] - servo[name][1]) / servo[name][0]
        out.append(Recording(r.path, r.time, cols))
    return out


def main(split, work):
    false = units = signs = zeros = with_hinge = total = 0
    for case in sysid_cases.split_cases(split):
        folder = os.path.join(work, case.label)
        di.case_files(case, folder)
        model = os.path.join(folder, "nominal.xml")
        m = mujoco.MjModel.from_xml_path(model)
        recs = load_all([os.path.join(folder, f"train_{i}.csv") for i in (0, 1)], m)
        system = System(model, dt=recs[0].dt)
        z0 = np.array(system.spec.default, float)
        H = max(10, int(round(0.1 / recs[0].dt)))  # 0.1 s predictions
        every = [j for j in range(m.njnt) if int(m.jnt_type[j]) in OTHER]
        hinges = [j for j in every if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE)]
        said = [logged_units(system, z0, [from_recording(r, system) for r in rs], H) for rs in
                (recs, relogged(recs, m, 0, every), relogged(recs, m, 1, every[:1]),
                 relogged(recs, m, 2, hinges[:1]) if hinges else None) if rs is not None]
        total += 1
        false, units, signs = false + bool(said[0]), units + bool(said[1]), signs + bool(said[2])
        zeros, with_hinge = zeros + bool(said[3:] and said[3]), with_hinge + bool(hinges)
        print(f"{case.label} | as logged: {said[0][120:] or '-'} | degrees and mm: {said[1][120:] or 'no hint'} | "
              f"{system.joints[every[0]]} flipped: {said[2][120:] or 'no hint'} | "
              + (f"{system.joints[hinges[0]]} from half a turn: {said[3][120:] or 'no hint'}" if hinges else "no hinge"),
              flush=True)
    print(f"{split}: {total} cases; a hint as logged (false) {false}; a hint in degrees and mm {units}; "
          f"a hint with one joint's sign flipped {signs}; a hint with one hinge's zero half a turn away {zeros} "
          f"of {with_hinge} with a hinge")


def real():
    import real_datasets

    from sim2real.sysid.diagnose import _model_for_loading

    for name, run in real_datasets._runs().items():
        if "swapped" in name or "offset" in name:  # (the same recordings)
            continue
        m = _model_for_loading(run.model)
        recs = load_all(list(run.recordings), m)
        system = System(run.model, dt=recs[0].dt)
        trajs = [from_recording(r, system) for r in recs]
        for seconds in (0.05, 0.1, 0.3):
            H = max(5, int(round(seconds / recs[0].dt)))
            print(f"{name} | {seconds:g} s | {logged_units(system, np.array(system.spec.default, float), trajs, H) or '-'}",
                  flush=True)


if __name__ == "__main__":
    if sys.argv[1] == "real":
        real()
    else:
        main(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else "/tmp/units_check")
