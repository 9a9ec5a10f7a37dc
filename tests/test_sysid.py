"""Diagnosis tool: recording validation, concealed effects found, EMPS hardware data, atomic output."""
import dataclasses
import json
import os
import subprocess
import sys

import mujoco
import numpy as np
import pytest

from sim2real.envs.base import ASSETS
from sim2real.sysid import emps
from sim2real.sysid.diagnose import DiagnoseConfig, diagnose
from sim2real.sysid.generator import Case, record
from sim2real.sysid.recordings import RecordingError, load, load_all, save_csv

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PENDULUM = os.path.join(ASSETS, "pendulum.xml")


def _model():
    return mujoco.MjModel.from_xml_path(PENDULUM)


def _good(n=50, dt=0.01):
    t = np.arange(n) * dt
    return t, {"qpos:hinge": np.sin(t), "ctrl:motor": np.cos(t)}


def _write(tmp_path, name, header, rows):
    p = tmp_path / name
    p.write_text(",".join(header) + "\n" + "\n".join(",".join(str(v) for v in r) for r in rows) + "\n")
    return str(p)


# --------------------------------------------------------------------------------------------
# bad input: a clear error naming file, column or row

def test_good_recording_loads(tmp_path):
    t, cols = _good()
    p = str(tmp_path / "ok.csv")
    save_csv(p, t, cols)
    rec = load(p, _model())
    assert len(rec) == 50 and rec.dt == pytest.approx(0.01)
    np.testing.assert_allclose(rec.get("qpos", "hinge"), np.sin(t), atol=1e-8)


@pytest.mark.parametrize("case,match", [
    ("no_time", "no 'time' column"),
    ("unknown_joint", "column 'qpos:elbow' names joint 'elbow'.*model joints: hinge"),
    ("unknown_kind", "unknown column 'angle:hinge'"),
    ("missing_ctrl", "missing command column.*ctrl:motor"),
    ("nan_row", "non-finite value nan in column 'qpos:hinge' at data row 7"),
    ("duplicated_time", "duplicated time .* at data rows 10 and 11"),
    ("backwards_time", "time goes backwards at data row 21"),
    ("ragged", "malformed CSV"),
])
def test_bad_recordings_name_the_problem(tmp_path, case, match):
    t, cols = _good()
    header = ["time", "qpos:hinge", "ctrl:motor"]
    rows = [[t[i], cols["qpos:hinge"][i], cols["ctrl:motor"][i]] for i in range(len(t))]
    if case == "no_time":
        header[0] = "t"
    elif case == "unknown_joint":
        header[1] = "qpos:elbow"
    elif case == "unknown_kind":
        header[1] = "angle:hinge"
    elif case == "missing_ctrl":
        header, rows = header[:2], [r[:2] for r in rows]
    elif case == "nan_row":
        rows[6][1] = "nan"
    elif case == "duplicated_time":
        rows[10][0] = rows[9][0]
    elif case == "backwards_time":
        rows[20][0] = rows[18][0] - 0.001
    elif case == "ragged":
        rows[3] = rows[3][:2]
    p = _write(tmp_path, f"{case}.csv", header, rows)
    with pytest.raises(RecordingError, match=match) as e:
        load(p, _model())
    assert p in str(e.value)


def test_different_sample_rates_rejected(tmp_path):
    a, b = str(tmp_path / "a.csv"), str(tmp_path / "b.csv")
    save_csv(a, *_good(dt=0.01))
    save_csv(b, *_good(dt=0.02))
    with pytest.raises(RecordingError, match="b.csv: sample rate 50 Hz differs"):
        load_all([a, b], _model())


def test_cli_bad_input_exits_nonzero_and_writes_nothing(tmp_path):
    t, cols = _good()
    cols["qpos:hinge"][5] = np.nan
    bad = str(tmp_path / "bad.csv")
    save_csv(bad, t, cols)
    out = tmp_path / "diag"
    r = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "diagnose.py"), f"model={PENDULUM}",
                        f"recordings=[{bad}]", f"out={out}"], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode != 0
    assert "bad.csv" in r.stderr and "qpos:hinge" in r.stderr and "row 6" in r.stderr
    assert not out.exists()
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".diagnosis-")]


def test_model_joints_must_match(tmp_path):
    """A recording of another system (no column for the model's joint) is refused by name."""
    arm = mujoco.MjModel.from_xml_path(os.path.join(ASSETS, "arm2.xml"))
    t, cols = _good()
    p = str(tmp_path / "pend.csv")
    save_csv(p, t, cols)
    with pytest.raises(RecordingError, match="names joint 'hinge'.*model joints: shoulder, elbow"):
        load(p, arm)


# --------------------------------------------------------------------------------------------
# concealed effects: the diagnosis sees only the nominal model and the recordings

def _diagnose_case(tmp_path, case):
    train, held = str(tmp_path / "train.csv"), str(tmp_path / "held.csv")
    record(case, train)
    record(dataclasses.replace(case, seed=case.seed + 1000), held)
    return diagnose(DiagnoseConfig(model=PENDULUM, recordings=(train,), heldout=(held,), out=str(tmp_path / "d"),
                                   plots=False, progress=False,
                                   effects=("none", "coulomb_friction", "viscous_damping", "action_delay")))


def test_concealed_coulomb_friction_found_and_fitted(tmp_path):
    d = _diagnose_case(tmp_path, Case("pendulum", "coulomb_friction", "hinge", (("coulomb:hinge", 0.15),), seed=0))
    sel = d["effects"][0]
    assert (sel["effect"], sel["target"]) == ("coulomb_friction", "hinge")
    assert sel["params"]["coulomb:hinge"] == pytest.approx(0.15, rel=0.1)
    assert d["fit"]["after"] < 0.7 * d["fit"]["before"]
    with open(tmp_path / "d" / "diagnosis.json") as f:
        assert json.load(f)["effects"][0]["effect"] == "coulomb_friction"


def test_parameter_only_mismatch_names_no_effect(tmp_path):
    d = _diagnose_case(tmp_path, Case("pendulum", "none", "", (), (("mass:pole", 1.3),), seed=100))
    assert d["effects"][0]["effect"] == "none"
    assert d["fitted_params"]["mass:pole"] == pytest.approx(1.3, rel=0.05)


def test_effects_the_data_cannot_separate_are_reported(tmp_path):
    # a 1.5-step delay in front of the prismatic drive's stiff PD loop: a ~2 ms motor lag predicts
    # the same motion to within the sensor noise, so whichever comes first, the other is reported
    train, held = str(tmp_path / "train.csv"), str(tmp_path / "held.csv")
    case = Case("prismatic", "action_delay", "", (("action_delay", 1.5),), noise=1e-6, seed=4)
    record(case, train)
    record(dataclasses.replace(case, seed=1004), held)
    d = diagnose(DiagnoseConfig(model=os.path.join(ASSETS, "prismatic.xml"), recordings=(train,), heldout=(held,),
                                out=str(tmp_path / "d"), plots=False, progress=False,
                                effects=("none", "action_delay", "motor_lag")))
    named = {d["effects"][0]["effect"]} | {r["effect"] for r in d["indistinguishable"]}
    assert named == {"action_delay", "motor_lag"}
    assert d["confidence"] < 0.6
    assert any(n.startswith("indistinguishable") for n in d["notes"])


def test_ties_are_within_tolerance_of_the_selection():
    from sim2real.sysid.identify import ties
    verified = {"none": 0.1004, "action_delay": 0.100, "motor_lag@drive": 0.1005, "backlash@drive": 0.2}
    assert ties(verified, "action_delay", 0.01) == ["motor_lag@drive"]   # none is not an effect
    assert ties(verified, "action_delay", 0.001) == []
    assert ties({"none": 1.0, "backlash@drive": 1.0}, "none", 0.01) == []  # nothing to be confused with


# --------------------------------------------------------------------------------------------
# real hardware: the bundled EMPS data (the demo)

def test_emps_hardware_diagnosis(tmp_path):
    recs = emps.recordings(str(tmp_path / "recs"))
    out = tmp_path / "emps"
    d = diagnose(DiagnoseConfig(model=emps.NOMINAL_XML, recordings=(recs["estimation"],),
                                heldout=(recs["validation"],), out=str(out), progress=False))
    sel = d["effects"][0]
    assert (sel["effect"], sel["target"]) == ("coulomb_friction", "axis")
    fc = sel["params"]["coulomb:axis"]
    assert abs(fc - emps.REFERENCE["Fc"]) < 0.15 * emps.REFERENCE["Fc"]
    offset = fc * sel["params"]["coulomb_asym:axis"]  # the constant force offset during motion
    assert offset == pytest.approx(emps.REFERENCE["offset"], rel=0.3)
    assert d["fit"]["reduction"] >= 0.3
    assert d["indistinguishable"] == []
    for f in ("diagnosis.json", "report.md", "fitted.xml", "overlay.png"):
        assert (out / f).exists(), f
    fitted = mujoco.MjModel.from_xml_path(str(out / "fitted.xml"))
    assert fitted.dof_frictionloss[0] == pytest.approx(fc, rel=1e-4)
    assert fitted.body_mass[1] == pytest.approx(d["fitted_params"]["mass:carriage"], rel=1e-4)


# --------------------------------------------------------------------------------------------
# predictions on a recording's tail carry the command path's state from its start

def test_tail_predictions_keep_the_effect_state(tmp_path):
    """A prediction segment late in a recording starts the motor-lag filter where the recording
    left it; slicing the recording instead restarts it from rest (and biases the comparison)."""
    from sim2real.sysid.derivatives import window_for
    from sim2real.sysid.diagnose import predictions
    from sim2real.sysid.generator import _plant

    case = Case("pendulum", "motor_lag", "motor", (("motor_lag:motor", 0.1),), noise=0.0, seed=3)
    path = str(tmp_path / "lag.csv")
    truth = record(case, path)
    system, sim = _plant("pendulum")
    rec = load_all([path], system.mj, "test")[0]
    z = system.spec.vector(truth)
    win, H, first = window_for(rec.dt), 50, 1500
    tail = predictions(system, sim, z, rec, H, win, first=first)["qpos:hinge"]
    assert np.all(np.isnan(tail[:first + 1])) and np.isfinite(tail[first + 1: first + 1 + H]).all()
    full = predictions(system, sim, z, rec, H, win)["qpos:hinge"]
    np.testing.assert_allclose(tail[first + 1:], full[first + 1:], atol=1e-6)  # same segments, same state
    meas = rec.get("qpos", "hinge")
    sliced = predictions(system, sim, z, rec.slice(first, len(rec)), H, win)["qpos:hinge"]
    err = lambda p: np.sqrt(np.nanmean((p - meas[first:]) ** 2))  # noqa: E731
    assert err(tail[first:]) < 0.5 * err(sliced)
