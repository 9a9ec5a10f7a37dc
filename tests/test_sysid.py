"""Diagnosis tool: recording validation, concealed effects found, EMPS hardware data, atomic output."""
import dataclasses
import json
import os

import jax
import jax.numpy as jnp
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


def test_parquet_recording_loads_like_the_csv_and_names_its_problems(tmp_path):
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    t, cols = _good()
    save_csv(str(tmp_path / "ok.csv"), t, cols)
    table = {"time": t, **cols}
    pq.write_table(pa.table(table), str(tmp_path / "ok.parquet"))
    a, b = load(str(tmp_path / "ok.csv"), _model()), load(str(tmp_path / "ok.parquet"), _model())
    np.testing.assert_allclose(b.get("qpos", "hinge"), a.get("qpos", "hinge"), atol=1e-8)
    assert b.dt == pytest.approx(a.dt)
    gap = pa.array([float(v) if i != 7 else None for i, v in enumerate(cols["qpos:hinge"])])  # a null in the 8th row
    pq.write_table(pa.table({"time": t, "qpos:hinge": gap, "ctrl:motor": cols["ctrl:motor"]}), str(tmp_path / "gap.parquet"))
    with pytest.raises(RecordingError, match="gap.parquet: non-finite value nan in column 'qpos:hinge' at data row 8"):
        load(str(tmp_path / "gap.parquet"), _model())
    pq.write_table(pa.table({"time": t, "qpos:hinge": ["x"] * len(t), "ctrl:motor": cols["ctrl:motor"]}),
                   str(tmp_path / "text.parquet"))
    with pytest.raises(RecordingError, match="text.parquet: column 'qpos:hinge' holds string, not numbers"):
        load(str(tmp_path / "text.parquet"), _model())


def test_text_tables_as_loggers_and_spreadsheets_write_them_load_like_the_csv(tmp_path):
    """Semicolons with decimal commas, tabs, comment lines, np.savetxt's commented header, a pandas
    index column and units after the names all read as the plain CSV does."""
    t, cols = _good()
    save_csv(str(tmp_path / "ok.csv"), t, cols)
    q, u = cols["qpos:hinge"], cols["ctrl:motor"]
    rows = [(float(a), float(b), float(c)) for a, b, c in zip(t, q, u)]
    layouts = {
        "semicolons.csv": "time;qpos:hinge;ctrl:motor\n" + "".join(f"{a!r};{b!r};{c!r}\n".replace(".", ",")
                                                                 for a, b, c in rows),
        "tabs.tsv": "time\tqpos:hinge\tctrl:motor\n" + "".join(f"{a!r}\t{b!r}\t{c!r}\n" for a, b, c in rows),
        "commented.csv": "# rig 3, 2026-12-07\ntime,qpos:hinge,ctrl:motor\n" + "".join(f"{a!r},{b!r},{c!r}\n"
                                                                                      for a, b, c in rows),
        "savetxt.txt": "# time qpos:hinge ctrl:motor\n" + "".join(f"{a!r} {b!r} {c!r}\n" for a, b, c in rows),
        "pandas.csv": ",time,qpos:hinge,ctrl:motor\n" + "".join(f"{i},{a!r},{b!r},{c!r}\n"
                                                               for i, (a, b, c) in enumerate(rows)),
        "units.csv": "time [s],qpos:hinge (rad),ctrl:motor [N m]\n" + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in rows),
    }
    ref = load(str(tmp_path / "ok.csv"), _model())
    for name, text in layouts.items():
        (tmp_path / name).write_text(text)
        rec = load(str(tmp_path / name), _model())
        assert sorted(rec.columns) == sorted(ref.columns), name
        for c in ref.columns:
            np.testing.assert_allclose(rec.columns[c], ref.columns[c], atol=1e-8, err_msg=name)
        np.testing.assert_allclose(rec.time, ref.time, atol=1e-12, err_msg=name)


def test_single_sample_glitches_are_set_to_their_neighbours_mean_with_a_note(tmp_path):
    """A position read wrong for one sample is put back, named by column and row; motion that bends
    sharply (a bounce off a stop, a chatter at the sample rate, a wrap of the angle) is left as it is."""
    rng = np.random.default_rng(0)
    t = np.arange(600) * 0.005
    clean = 0.8 * np.sin(3 * t) + rng.normal(0, 1e-3, len(t))
    q = clean.copy()
    q[[100, 250, 401]] += [0.3, -0.05, 0.02]
    save_csv(str(tmp_path / "glitchy.csv"), t, {"qpos:hinge": q, "ctrl:motor": np.cos(t)})
    rec = load(str(tmp_path / "glitchy.csv"), _model())
    assert [n for n in rec.notes if "glitch" in n] == [
        "glitchy: 3 single-sample glitches in 'qpos:hinge' (data rows 101, 251, 402) set to the mean of their neighbours"]
    assert np.abs(rec.get("qpos", "hinge") - clean).max() < 0.01
    bounce = 0.5 - np.abs(np.sin(2 * t)) * 0.5 + rng.normal(0, 1e-3, len(t))   # kinks at every reversal
    chatter = 0.3 * np.sin(t) + 0.02 * (-1.0) ** np.arange(len(t)) * (t > 1.5)  # a servo chattering
    wrapped = np.angle(np.exp(1j * (3.05 + 0.1 * np.sin(9 * t) + rng.normal(0, 0.02, len(t)))))  # about +-pi
    for name, x in (("bounce", bounce), ("chatter", chatter), ("wrapped", wrapped)):
        save_csv(str(tmp_path / f"{name}.csv"), t, {"qpos:hinge": x, "ctrl:motor": np.cos(t)})
        rec = load(str(tmp_path / f"{name}.csv"), _model())
        assert not [n for n in rec.notes if "glitch" in n], name
        np.testing.assert_allclose(rec.get("qpos", "hinge"), x, atol=1e-8)


JOINT_STATE = """std_msgs/Header header
string[] name
float64[] position
float64[] velocity
float64[] effort
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""


def _write_mcap(path, t, cols, command_stamps=None):
    from mcap_ros2.writer import Writer

    with open(path, "wb") as f:
        w = Writer(f)
        schema = w.register_msgdef("sensor_msgs/msg/JointState", JOINT_STATE)
        for topic, stamps, name, fields in (("/joint_states", t, "hinge", {"position": cols["qpos:hinge"]}),
                                            ("/joint_commands", command_stamps if command_stamps is not None else t,
                                             "motor", {"effort": cols["ctrl:motor"]})):
            for i, ti in enumerate(stamps):
                sec = int(np.floor(ti))
                msg = {"header": {"stamp": {"sec": sec, "nanosec": int(round((ti - sec) * 1e9))}, "frame_id": ""},
                       "name": [name], "position": [], "velocity": [], "effort": []}
                msg.update({k: [float(v[i])] for k, v in fields.items()})
                w.write_message(topic, schema, msg, log_time=int(ti * 1e9), publish_time=int(ti * 1e9))
        w.finish()


def test_mcap_joint_states_load_like_the_csv(tmp_path):
    pytest.importorskip("mcap_ros2")
    t, cols = _good()
    t = t + 1.7e9  # ROS wall-clock stamps: the time need not start at 0
    save_csv(str(tmp_path / "ok.csv"), t - t[0], cols)
    _write_mcap(str(tmp_path / "ok.mcap"), t, cols)
    a, b = load(str(tmp_path / "ok.csv"), _model()), load(str(tmp_path / "ok.mcap"), _model())
    np.testing.assert_allclose(b.get("qpos", "hinge"), a.get("qpos", "hinge"), atol=1e-8)
    np.testing.assert_allclose(b.get("ctrl", "motor"), a.get("ctrl", "motor"), atol=1e-8)
    assert b.dt == pytest.approx(0.01, rel=1e-5)
    _write_mcap(str(tmp_path / "skew.mcap"), t, cols, command_stamps=t + 0.003)
    with pytest.raises(RecordingError, match="skew.mcap: topic '/joint_commands' is not stamped at the instants"):
        load(str(tmp_path / "skew.mcap"), _model())


@pytest.mark.parametrize("case,match", [
    ("no_time", "no 'time' column"),
    ("unknown_joint", "column 'qpos:elbow' names joint 'elbow'.*model joints: hinge"),
    ("unknown_kind", "unknown column 'angle:hinge'"),
    ("missing_ctrl", "missing command column.*ctrl:motor"),
    ("nan_row", "non-finite value nan in column 'qpos:hinge' at data row 7"),
    ("duplicated_time", "duplicated time .* at data rows 10 and 11"),
    ("backwards_time", "time goes backwards at data row 21"),
    ("ragged", "malformed CSV: data row 4 has 2 values"),
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


def test_model_joints_must_match(tmp_path):
    """A recording of another system (no column for the model's joint) is refused by name."""
    arm = mujoco.MjModel.from_xml_path(os.path.join(ASSETS, "arm2.xml"))
    t, cols = _good()
    p = str(tmp_path / "pend.csv")
    save_csv(p, t, cols)
    with pytest.raises(RecordingError, match="names joint 'hinge'.*model joints: shoulder, elbow"):
        load(p, arm)


# --------------------------------------------------------------------------------------------
# concealed effects (the model-matched generator): the diagnosis sees only the nominal model

def _diagnose_case(tmp_path, case, effects=("none", "coulomb_friction", "viscous_damping", "action_delay")):
    train, held = str(tmp_path / "train.csv"), str(tmp_path / "held.csv")
    record(case, train)
    record(dataclasses.replace(case, seed=case.seed + 1000), held)
    return diagnose(DiagnoseConfig(model=PENDULUM, recordings=(train,), heldout=(held,), out=str(tmp_path / "d"),
                                   plots=False, progress=False, effects=effects))


def test_concealed_coulomb_friction_found_and_fitted(tmp_path):
    d = _diagnose_case(tmp_path, Case("pendulum", "coulomb_friction", "hinge", (("coulomb:hinge", 0.15),), seed=0))
    assert d["answer"] == "effects"
    assert [(s["effect"], s["target"]) for s in d["selected"]] == [("coulomb_friction", "hinge")]
    assert d["selected"][0]["params"]["coulomb:hinge"] == pytest.approx(0.15, rel=0.1)
    assert d["fit"]["after"] < 0.7 * d["fit"]["before"]
    with open(tmp_path / "d" / "diagnosis.json") as f:
        assert json.load(f)["selected"][0]["effect"] == "coulomb_friction"


def test_parameter_only_mismatch_names_no_effect(tmp_path):
    d = _diagnose_case(tmp_path, Case("pendulum", "none", "", (), (("mass:pole", 1.3),), seed=100))
    assert d["answer"] == "none" and d["selected"] == []
    assert d["fitted_params"]["mass:pole"] == pytest.approx(1.3, rel=0.05)


# --------------------------------------------------------------------------------------------
# real hardware: the bundled EMPS data (the demo)

@pytest.mark.optimized  # runs long (see conftest.py)
def test_emps_hardware_diagnosis(tmp_path):
    out = tmp_path / "emps"
    d = diagnose(DiagnoseConfig(model=emps.NOMINAL_XML, recordings=(emps.RECORDINGS["estimation"],),
                                heldout=(emps.RECORDINGS["validation"],), out=str(out), progress=False))
    sel = {s["effect"]: s for s in d["selected"]}
    assert "coulomb_friction" in sel and sel["coulomb_friction"]["target"] == "axis"
    p = sel["coulomb_friction"]["params"]
    fc = p["coulomb:axis"]
    assert abs(fc - emps.REFERENCE["Fc"]) < 0.15 * emps.REFERENCE["Fc"]
    offset = fc * p.get("coulomb_asym:axis", 0.0)  # the constant force offset during motion
    assert offset == pytest.approx(emps.REFERENCE["offset"], rel=0.3)
    assert d["fit"]["reduction"] >= 0.3
    for f in ("diagnosis.json", "report.md", "report.html", "fitted.xml", "overlay.png", "heldout_segments.png", ".sim2real"):
        assert (out / f).exists(), f
    # the HTML page stands alone: every figure of report.md embedded, none linked
    page, md = (out / "report.html").read_text(), (out / "report.md").read_text()
    assert page.count("data:image/") == md.count("](") == len(d["figures"]) > 0
    assert "<code>coulomb:axis</code>" in page and "95% interval" in page and 'src="overlay.png"' not in page
    # the estimates' correlation (symmetric, unit diagonal) and a figure of it; the regime table
    # holds the fitted model's residual beside the nominal's (the chart compares the two)
    c = np.array(d["correlation"]["matrix"], float)
    assert d["correlation"]["names"] == list(d["correlation"]["names"]) and c.shape == (len(c), len(c)) and len(c) >= 2
    assert np.allclose(c, c.T) and np.allclose(np.diag(c), 1.0) and "correlation.png" in d["figures"]
    regimes = [r for r in d["mismatch"]["regimes"]["axis"].values() if r["rms"] is not None]
    assert regimes and all("rms_fitted" in r for r in regimes)
    # the held-out window animated, wherever there is headless OpenGL to draw it with
    gif = "heldout.gif" in d["figures"]
    assert gif or any("heldout.gif was not drawn" in n for n in d["notes"])
    if gif:
        assert "data:image/gif;base64," in page
    fitted = mujoco.MjModel.from_xml_path(str(out / "fitted.xml"))
    assert fitted.dof_frictionloss[0] == pytest.approx(fc, rel=1e-4)
    assert fitted.body_mass[1] == pytest.approx(d["fitted_params"]["mass:carriage"], rel=1e-4)
    # the asymmetry as a constant force MuJoCo simulates: a bias-only actuator after the model's own
    bias = mujoco.mj_name2id(fitted, mujoco.mjtObj.mjOBJ_ACTUATOR, "sim2real_friction_offset:axis")
    assert bias == fitted.nu - 1 and fitted.actuator_gainprm[bias, 0] == 0.0
    assert fitted.actuator_biasprm[bias, 0] == pytest.approx(-offset, rel=1e-4)
    assert "written as a constant force" in (out / "fitted.xml").read_text()


# --------------------------------------------------------------------------------------------
# a segment late in a recording starts its command path where the recording left it

def test_segments_start_the_command_path_from_the_recording(tmp_path):
    """Motor lag of 0.1 s: every segment's lag filter starts from running the commands from the
    recording's start (pass 1 of ``Shooting``), so the true physics predicts every segment; a
    segment whose filter started from rest would not."""
    from sim2real.sysid.fit import Fitter
    from sim2real.sysid.shooting import Shooting
    from sim2real.sysid.system import System
    from sim2real.sysid.trajectory import from_recording

    case = Case("pendulum", "motor_lag", "motor", (("motor_lag:motor", 0.1),), noise=0.0, seed=3)
    path = str(tmp_path / "lag.csv")
    truth = record(case, path)
    rec = load(path, _model())
    system = System(PENDULUM, dt=rec.dt)
    sh = Shooting(system, [from_recording(rec, system)], 20, val_fraction=0.3)
    z = system.spec.vector(truth)
    tiles = sh.tiles.of("fit")[1:]                       # segments after the first
    fitter = Fitter(sh, {})
    r = fitter.residuals(np.stack([z, system.spec.default]), np.repeat(sh.v0[None], 2, 0), tiles)
    assert np.sqrt(np.mean(r[0] ** 2)) < 0.05 * np.sqrt(np.mean(r[1] ** 2))
    # the same segments simulated with the filter restarted from rest at each start are worse
    es0 = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x, (sh.S,) + x.shape), system.effects.init_state())
    restarted = sh._segments(jnp.asarray(z)[None], jnp.asarray(sh.v0, jnp.float32)[None], jnp.asarray(tiles), sh._data,
                             jax.tree_util.tree_map(lambda x: x[None], es0), jnp.zeros((1, sh.S, 0)))
    e_restart = np.asarray(restarted["qpos"][0]) - sh.signals["qpos"][tiles]
    e_pass1 = sh.predict(z[None], sh.v0[None], tiles)["qpos"][0] - sh.signals["qpos"][tiles]
    assert np.sqrt(np.mean(e_pass1 ** 2)) < 0.5 * np.sqrt(np.mean(e_restart ** 2))
    # the diagnosis' precision=64: the same simulator in float64 (the lag's state carried in it)
    with jax.enable_x64(True):
        system64 = System(PENDULUM, dt=rec.dt)
        sh64 = Shooting(system64, [from_recording(rec, system64)], 20, val_fraction=0.3)
        q64 = sh64.predict(z[None], sh.v0[None], tiles)["qpos"][0]
    assert q64.dtype == np.float64
    np.testing.assert_allclose(q64, e_pass1 + sh.signals["qpos"][tiles], rtol=0, atol=1e-4)


def test_a_batch_without_a_band_is_replayed_without_the_band(tmp_path, monkeypatch):
    """Where no physics of a call has a backlash, the command path is replayed without the band's
    sums (``Effects.skippable``): the predictions are those of the full replay, and of a batch with
    a band beside them the band's lane is the band's."""
    from sim2real.sysid.shooting import Shooting
    from sim2real.sysid.system import System
    from sim2real.sysid.trajectory import from_recording

    case = Case("pendulum", "motor_lag", "motor", (("motor_lag:motor", 0.1),), noise=0.0, seed=3)
    path = str(tmp_path / "lag.csv")
    record(case, path)
    rec = load(path, _model())
    system = System(PENDULUM, dt=rec.dt)
    assert system.effects.skippable == ("backlash",)
    z_lag = system.spec.vector({"motor_lag:motor": 0.1})
    z_band = system.spec.vector({"backlash:motor": 0.05})
    sh = Shooting(system, [from_recording(rec, system)], 20, val_fraction=0.3)
    tiles = sh.tiles.of("fit")
    v0 = np.repeat(sh.v0[None], 2, 0)
    skipped = sh.predict(np.stack([z_lag, z_lag]), v0, tiles)["qpos"]
    mixed = sh.predict(np.stack([z_lag, z_band]), v0, tiles)["qpos"]
    monkeypatch.setattr(system.effects, "skippable", ())
    full = Shooting(system, [from_recording(rec, system)], 20, val_fraction=0.3)
    np.testing.assert_allclose(skipped[0], full.predict(z_lag[None], v0[:1], tiles)["qpos"][0], rtol=0, atol=1e-6)
    np.testing.assert_allclose(mixed, full.predict(np.stack([z_lag, z_band]), v0, tiles)["qpos"], rtol=0, atol=1e-6)
    assert np.abs(mixed[1] - mixed[0]).max() > 1e-3     # (the band's lane is not the lag's)


def test_a_fit_started_outside_its_range_ends_inside(tmp_path):
    """A start above a parameter's search range (``bounds``) is brought inside before the first
    step: every step is clipped into the range, so a fit left at such a start rejected them all
    and stayed out (the IBM double pendulum's payloads, scaled with the masses, at 4-5x the top
    of their range). Here a motor lag of 0.1 s fitted within (0, 0.05) s from the truth: every
    clipped step predicts worse than the start, so without the clip the fit ends at 0.1."""
    from sim2real.sysid.fit import Fitter
    from sim2real.sysid.shooting import Shooting
    from sim2real.sysid.system import System
    from sim2real.sysid.trajectory import from_recording

    case = Case("pendulum", "motor_lag", "motor", (("motor_lag:motor", 0.1),), noise=0.0, seed=3)
    path = str(tmp_path / "lag.csv")
    record(case, path)
    rec = load(path, _model())
    system = System(PENDULUM, dt=rec.dt)
    sh = Shooting(system, [from_recording(rec, system)], 20, val_fraction=0.3)
    z0 = system.spec.vector({"motor_lag:motor": 0.1})
    r = Fitter(sh, {"motor_lag:motor": 0.02}).fit(z0, sh.v0, ["motor_lag:motor"], sh.tiles.of("fit"), iters=3,
                                                  bounds={"motor_lag:motor": (0.0, 0.05)})
    assert 0.0 <= r.z[system.spec.index("motor_lag:motor")] <= 0.05


_PREDICT = """
import sys
import numpy as np
from sim2real.envs import parallel
parallel.use_cpu_cores(int(sys.argv[3]))
import jax
from sim2real.envs.base import ASSETS
import mujoco, os
from sim2real.sysid.recordings import load
from sim2real.sysid.shooting import Shooting
from sim2real.sysid.system import System
from sim2real.sysid.trajectory import from_recording
model = os.path.join(ASSETS, "pendulum.xml")
rec = load(sys.argv[1], mujoco.MjModel.from_xml_path(model))
system = System(model, dt=rec.dt)
sh = Shooting(system, [from_recording(rec, system)], 20, val_fraction=0.3)
z = np.stack([system.spec.default, system.spec.vector({"motor_lag:motor": 0.1})])
out = sh.predict(z, np.repeat(sh.v0[None], 2, 0), sh.tiles.of("fit"))
np.savez(sys.argv[2], devices=len(jax.devices()), **out)
"""


def test_predictions_split_over_two_cpu_devices_are_the_ones_of_one(tmp_path):
    """The diagnose command asks for one CPU device per core (``envs.parallel.use_cpu_cores``) and
    ``Shooting`` then splits its physics vectors over them: the predictions are those of a single
    device (two fresh processes: the device count is fixed when JAX starts)."""
    import subprocess
    import sys

    case = Case("pendulum", "motor_lag", "motor", (("motor_lag:motor", 0.1),), noise=0.0, seed=3)
    path = str(tmp_path / "lag.csv")
    record(case, path)
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    res = {}
    for n in (1, 2):
        out = str(tmp_path / f"pred{n}.npz")
        p = subprocess.run([sys.executable, "-c", _PREDICT, path, out, str(n)], env=env, cwd=ROOT,
                           capture_output=True, text=True)
        assert p.returncode == 0, p.stderr[-2000:]
        res[n] = dict(np.load(out))
    assert res[1]["devices"] == 1 and res[2]["devices"] == 2
    assert res[1]["qpos"].shape == res[2]["qpos"].shape == (2, len(res[1]["ok"][0])) + res[1]["qpos"].shape[2:]
    assert not np.allclose(res[1]["qpos"][0], res[1]["qpos"][1])   # two different physics
    for key in ("qpos", "qvel", "force"):
        np.testing.assert_allclose(res[2][key], res[1][key], rtol=1e-5, atol=1e-6)


def test_a_measured_velocity_noisier_than_the_motion_is_not_compared(tmp_path):
    """A ``qvel`` column whose noise is larger than the motion it measures (an encoder's count
    differenced at a fast rate) adds about one per residual to every model and dilutes every
    relative measure: the segments leave it out (and the predictions' ``qvel`` with it). The
    same column measured precisely is compared."""
    import csv

    from sim2real.sysid.shooting import Shooting
    from sim2real.sysid.system import System
    from sim2real.sysid.trajectory import from_recording

    case = Case("pendulum", "motor_lag", "motor", (("motor_lag:motor", 0.1),), noise=0.0, seed=3)
    path = str(tmp_path / "lag.csv")
    record(case, path)
    rows = list(csv.reader(open(path)))
    t = np.array([float(r[0]) for r in rows[1:]])
    q = np.array([float(r[rows[0].index("qpos:hinge")]) for r in rows[1:]])
    v = np.gradient(q, t)
    system = System(PENDULUM, dt=float(t[1] - t[0]))
    rng = np.random.default_rng(0)
    kept = {}
    for name, noise in (("precise", 1e-3), ("noisy", 3.0)):
        vm = v + noise * np.std(v) * rng.standard_normal(len(v))
        out = str(tmp_path / f"{name}.csv")
        with open(out, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(rows[0] + ["qvel:hinge"])
            w.writerows(r + [f"{x:.9g}"] for r, x in zip(rows[1:], vm))
        sh = Shooting(system, [from_recording(load(out, _model()), system)], 20, val_fraction=0.3)
        pred = sh.predict(system.spec.default[None], sh.v0[None], sh.tiles.of("fit"))
        kept[name] = ("qvel" in sh.signals, sh.left_out, pred["qvel"].shape[-1])
    assert kept["precise"] == (True, [], 1)
    assert kept["noisy"] == (False, ["qvel:hinge"], 0)


def test_fitted_xml_scales_the_gain_law_as_the_simulator_does(tmp_path):
    """A motor and a position servo with their gains (and the servo's kv) off the declared values:
    the compiled fitted.xml holds the same gain/bias parameters as the model the fits simulate."""
    from sim2real.physics.model_apply import to_mjmodel
    from sim2real.sysid.export import write_fitted_mjcf
    from sim2real.sysid.system import System

    xml = tmp_path / "arm.xml"
    xml.write_text("""<mujoco><option timestep="0.002"/><worldbody>
      <body name="a"><joint name="j1" type="hinge" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/>
        <body name="b" pos="0 0 -0.3"><joint name="j2" type="hinge" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" mass="0.2"/></body>
      </body></worldbody>
      <actuator><motor name="m1" joint="j1" gear="5"/><position name="p2" joint="j2" kp="8" kv="0.5"/></actuator></mujoco>""")
    system = System(str(xml))
    sp = system.spec
    z = np.array(sp.default, float)
    scale = {"gain:m1": 1.5, "gain:p2": 2.0, "kv:p2": 3.0}
    for name, f in scale.items():
        z[sp.index(name)] *= f
    simulated = to_mjmodel(system.physics, z)
    write_fitted_mjcf(str(xml), system, z, {}, str(tmp_path / "fitted.xml"))
    fitted = mujoco.MjModel.from_xml_path(str(tmp_path / "fitted.xml"))
    for field in ("actuator_gainprm", "actuator_biasprm"):
        np.testing.assert_allclose(getattr(fitted, field)[:, :3], getattr(simulated, field)[:, :3], rtol=1e-5)
    declared = mujoco.MjModel.from_xml_path(str(xml))
    assert fitted.actuator_gainprm[1, 0] == pytest.approx(2.0 * declared.actuator_gainprm[1, 0])
    assert fitted.actuator_biasprm[1, 1] == pytest.approx(2.0 * declared.actuator_biasprm[1, 1])  # -kp follows kp
    assert fitted.actuator_biasprm[1, 2] == pytest.approx(3.0 * declared.actuator_biasprm[1, 2])


def test_contacts_mjx_cannot_compute_are_left_out_where_no_recorded_pose_touches(tmp_path):
    """A cylinder link beside a box on the world: MJX has no cylinder-box collision and its
    ``put_model`` refuses the model. The pair is left out (with a note); a recording that swings
    the link into the box is refused at the row where they touch; a declared ``<pair>`` of them
    is refused."""
    from sim2real.sysid.system import ModelError, System

    xml = """<mujoco><worldbody><geom name="stop" type="box" pos="0.3 0 1" size="0.05 0.05 0.05"/>
      <body name="rod" pos="0 0 1"><joint name="hinge" axis="0 1 0"/>
      <geom name="link" type="cylinder" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/></body></worldbody>
      <actuator><motor name="m" joint="hinge"/></actuator>{pair}</mujoco>"""
    path = str(tmp_path / "stop.xml")
    open(path, "w").write(xml.format(pair=""))
    system = System(path, dt=0.01)
    assert len(system.left_out_contacts) == 1
    assert any("MJX cannot collide cylinder 'link' of rod with box 'stop' of world" in n and "'world' and 'rod'" in n
               for n in system.notes)
    angle = np.linspace(0.0, -1.6, 100)   # (the link's tip reaches the box near -pi/2)
    save_csv(str(tmp_path / "r.csv"), 0.01 * np.arange(100), {"qpos:hinge": angle, "ctrl:m": 0 * angle})
    # the first row where the link's axis (x-z plane) comes within its radius of the box's square
    s_ = np.linspace(0, 0.3, 301)[None]
    x, z = s_ * np.sin(-angle)[:, None], 1 - s_ * np.cos(angle)[:, None]
    gap = np.hypot(np.maximum(np.abs(x - 0.3) - 0.05, 0), np.maximum(np.abs(z - 1) - 0.05, 0)).min(1)
    touch = int(np.argmax(gap <= 0.02))
    with pytest.raises(ModelError, match=r"r.csv: at data row (\d+) .*cylinder 'link' of rod touches box 'stop'") as e:
        system.check_recording_covers(load(str(tmp_path / "r.csv"), system.mj))
    row = int(e.value.args[0].split("at data row ")[1].split()[0])
    assert abs(row - (touch + 1)) <= 1   # (flat end, round model)
    # the same swing after 20 samples at rest and 5 lost: the row named is the file's, not the piece's
    t = np.concatenate([0.01 * np.arange(20), 0.01 * np.arange(25, 125)])
    save_csv(str(tmp_path / "r.csv"), t, {"qpos:hinge": np.r_[np.zeros(20), angle], "ctrl:m": 0 * t})
    with pytest.raises(ModelError, match=rf"r.csv: at data row {row + 20} "):
        system.check_recording_covers(load_all([str(tmp_path / "r.csv")], system.mj)[1])
    save_csv(str(tmp_path / "r.csv"), 0.01 * np.arange(100), {"qpos:hinge": angle / 2, "ctrl:m": 0 * angle})
    system.check_recording_covers(load(str(tmp_path / "r.csv"), system.mj))   # (never nearer than 3 cm)
    open(path, "w").write(xml.format(pair='<contact><pair geom1="link" geom2="stop"/></contact>'))
    with pytest.raises(ModelError, match="the contact pair of cylinder 'link' of rod and box 'stop' of world is declared"):
        System(path, dt=0.01)


def test_contacts_no_recorded_pose_comes_near_are_left_out_of_the_simulation(tmp_path):
    """A capsule link and a sphere on the world that MJX would collide at every step: where the
    recorded swing keeps them 5 cm apart or more their contacts are left out (the System built
    with ``apart`` has no contact pair); a swing that brings the link
    within 1 cm keeps them."""
    from sim2real.sysid.system import System, _contact_pairs

    path = str(tmp_path / "ball.xml")
    open(path, "w").write("""<mujoco><worldbody><geom name="ball" type="sphere" pos="0.28 0 1" size="0.05"/>
      <body name="rod" pos="0 0 1"><joint name="hinge" axis="0 1 0"/>
      <geom name="link" type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" mass="0.4"/></body></worldbody>
      <actuator><motor name="m" joint="hinge"/></actuator></mujoco>""")
    system = System(path, dt=0.01)
    assert len(_contact_pairs(system.mj)) == 1
    t = 0.01 * np.arange(100)

    def swing(amplitude):   # (the link's tip, nearest the ball at the swing's end, moves up to 9 mm a sample)
        save_csv(str(tmp_path / "r.csv"), t, {"qpos:hinge": -amplitude * np.sin(t * 3), "ctrl:m": 0 * t})
        return system.bodies_apart([load(str(tmp_path / "r.csv"), system.mj)])

    apart, note = swing(0.6)   # nearest: |(0.28, 1) - (0.2 sin 0.6, 1 - 0.2 cos 0.6)| - 0.07 = 0.165 m
    assert apart == ((0, 1),) and "contacts of 1 of 1 body pairs left out" in note and "'world'-'rod'" in note
    assert _contact_pairs(System(path, dt=0.01, apart=apart).mj) == []
    assert swing(1.5) == ((), "")   # nearest 0.012 m: within 1 cm and a sample's travel


def test_range_limits_no_recorded_position_comes_near_are_left_out_of_the_simulation(tmp_path):
    """A pendulum and a slide with ranges (MuJoCo limits a joint with a range): a swing that stays
    far inside the hinge's range leaves its limit out (the System built with ``unlimited`` has it
    off, and simulates the swing exactly as the limited model does); the slide, pushed to within
    a tenth of its span of an end, keeps its limit; a swing that nears the hinge's end keeps both.
    ``fitted.xml`` keeps every limit (the export starts from the user's file)."""
    import mujoco

    from sim2real.sysid.export import write_fitted_mjcf
    from sim2real.sysid.system import System

    path = str(tmp_path / "limited.xml")
    open(path, "w").write("""<mujoco><compiler angle="radian"/><worldbody>
      <body name="rod" pos="0 0 1"><joint name="hinge" axis="0 1 0" range="-2 2"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" mass="0.4"/>
      <body name="bead"><joint name="slide" type="slide" axis="0 0 1" range="-0.1 0.1"/>
      <geom type="sphere" size="0.02" mass="0.1"/></body></body></worldbody>
      <actuator><motor name="m" joint="hinge"/></actuator></mujoco>""")
    system = System(path, dt=0.01)
    t = 0.01 * np.arange(100)

    def clear(amplitude):
        save_csv(str(tmp_path / "r.csv"), t, {"qpos:hinge": amplitude * np.sin(t * 3), "qpos:slide": 0.085 + 0 * t,
                                              "ctrl:m": 0.1 * np.sin(t * 5)})
        return system.limits_clear([load(str(tmp_path / "r.csv"), system.mj)])

    unlimited, note = clear(1.0)   # 1 rad of room, 0.4 asked (a tenth of the span) plus a sample's 0.03
    assert unlimited == (0,) and "the range limits of 1 of 2 limited joints left out of the simulation (hinge)" in note
    unbound = System(path, dt=0.01, unlimited=unlimited)
    free = unbound.mj
    assert list(free.jnt_limited) == [0, 1] and list(system.mj.jnt_limited) == [1, 1]
    write_fitted_mjcf(path, unbound, np.array(unbound.spec.default, float), {}, str(tmp_path / "fitted.xml"))
    assert list(mujoco.MjModel.from_xml_path(str(tmp_path / "fitted.xml")).jnt_limited) == [1, 1]   # (kept there)
    runs = []
    for m in (system.mj, free):
        d = mujoco.MjData(m)
        d.qpos[:] = [0.0, 0.085]
        for k in range(100):
            d.ctrl[:] = 0.1 * np.sin(k * 0.05)
            mujoco.mj_step(m, d)
        runs.append(d.qpos.copy())
    np.testing.assert_array_equal(*runs)
    assert clear(1.7) == ((), "")   # 0.3 rad of room: within a tenth of the span


def test_recordings_logged_in_degrees_get_a_hint_and_radians_none(tmp_path):
    """A pendulum (native ``mj_step``, a 0.05 N m friction the model lacks) logged in radians, and
    the same angles written in degrees, counted the other way, and counted from upright:
    ``units.logged_units`` names the hinge and its unit, sign or zero, and says nothing for the
    radians; nor for a servo-driven slide logged in mm or flipped with its setpoints (a linear
    system with its commands in the joint's units and sign: the data cannot tell)."""
    import mujoco

    from sim2real.sysid.system import System
    from sim2real.sysid.trajectory import from_recording
    from sim2real.sysid.units import logged_units

    def recorded(xml, truth, name, cmd, col, act, *scales):
        path = str(tmp_path / f"{name}.xml")
        open(path, "w").write(xml.format(truth=""))
        m = mujoco.MjModel.from_xml_string(xml.format(truth=truth))
        d = mujoco.MjData(m)
        rows = []
        for k in range(800):   # 4 s at 200 Hz from 1 ms physics
            d.ctrl[:] = cmd(k * 0.005)
            rows.append((k * 0.005, d.qpos[0] + 1e-4 * np.sin(7.3 * k), d.ctrl[0]))
            for _ in range(5):
                mujoco.mj_step(m, d)
        t, q, u = map(np.array, zip(*rows))
        system = System(path, dt=0.005)
        hints = []
        for s, c in ((1.0, 0.0), *scales):   # (logged as s x the model's position + c)
            save_csv(str(tmp_path / "r.csv"), t, {col: q * s + c, act: u * (s if "slide" in name else 1.0)})
            tr = from_recording(load(str(tmp_path / "r.csv"), system.mj), system)
            hints.append(logged_units(system, np.array(system.spec.default, float), [tr], 20))
        return hints

    pendulum = """<mujoco><option timestep="0.001"/><worldbody><body name="rod" pos="0 0 1">
      <joint name="hinge" axis="0 1 0" damping="0.01" {truth}/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/></body></worldbody>
      <actuator><motor name="m" joint="hinge"/></actuator></mujoco>"""
    radians, degrees, flipped, upright = recorded(pendulum, 'frictionloss="0.05"', "pendulum",
                                                  lambda t: 0.8 * np.sin(2.1 * t) + 0.5 * np.sin(5.3 * t), "qpos:hinge",
                                                  "ctrl:m", (180 / np.pi, 0.0), (-1.0, 0.0), (1.0, -np.pi))
    assert radians == ""
    assert "read qpos:hinge as degrees (and their velocities)" in degrees and "convert the columns" in degrees
    assert "read qpos:hinge with its sign flipped (and their velocities)" in flipped
    assert "read qpos:hinge with its zero half a turn away" in upright
    slide = """<mujoco><option timestep="0.001"/><worldbody><body name="cart">
      <joint name="slide" type="slide" axis="1 0 0" damping="2" {truth}/>
      <geom type="box" size="0.05 0.05 0.02" mass="1"/></body></worldbody>
      <actuator><position name="p" joint="slide" kp="200" kv="10"/></actuator></mujoco>"""
    assert recorded(slide, 'frictionloss="1"', "slide", lambda t: 0.1 * np.sign(np.sin(3 * t)), "qpos:slide", "ctrl:p",
                    (1000.0, 0.0), (-1.0, 0.0)) == ["", "", ""]


def test_a_force_column_in_other_units_is_named():
    """``units.force_units``: a measured force 12.5x the model's (a current logged for a torque) is
    named with its factor; one 20% off (a gain the fit may take up), or one whose shape differs (a
    force limit the model lacks), is not."""
    from sim2real.sysid.units import force_units

    rng = np.random.default_rng(0)
    model = np.sin(np.linspace(0, 20, 400))[:, None] * np.array([1.0, 0.5])     # [T, 2]
    noisy = lambda f: f + rng.normal(0, 0.01, f.shape)   # noqa: E731
    said = force_units(["force:a", "force:b"], noisy(model * np.array([12.5, 1.0])), model)
    assert "force:a reads 12.5" in said and "force:b" not in said
    assert force_units(["force:a", "force:b"], noisy(model * 1.2), model) == ""
    assert force_units(["force:a", "force:b"], noisy(np.clip(model, -0.2, 0.2)), model) == ""


def test_commands_far_past_their_ctrlrange_are_noted(tmp_path):
    """A position servo's setpoints logged in mm (230 against a ctrlrange of +-0.3 m): MuJoCo clamps
    them, and the recording's notes say so, naming the column, the share of rows and the largest
    value's row; commands within a span of the range (a controller's output past it) are not noted."""
    import mujoco

    m = mujoco.MjModel.from_xml_string("""<mujoco><worldbody><body><joint name="x" type="slide"/>
      <geom size="0.05" mass="1"/></body></worldbody>
      <actuator><position name="p" joint="x" kp="100" ctrlrange="-0.3 0.3"/></actuator></mujoco>""")
    t = 0.01 * np.arange(100)
    path = str(tmp_path / "r.csv")
    for setpoint, noted in ((230e-3 * np.sin(t), False), (230 * np.sin(t), True)):
        save_csv(path, t, {"qpos:x": setpoint, "ctrl:p": setpoint})
        notes = [n for n in load(path, m).notes if "ctrlrange" in n]
        assert bool(notes) == noted
    assert "column 'ctrl:p' lies beyond the actuator's ctrlrange [-0.3, 0.3]" in notes[0]
    assert "data row 100" in notes[0] and "(a setpoint in mm or degrees?)" in notes[0]


def test_fitted_xml_of_a_model_with_meshes_loads_from_the_diagnosis_folder(tmp_path):
    """A link drawn from a mesh under the model's ``meshdir``: the fitted file, written in another
    folder, finds the same mesh (it did not load there: "Error opening file 'assets/link.obj'")."""
    from sim2real.sysid.export import write_fitted_mjcf
    from sim2real.sysid.system import System

    robot = tmp_path / "robot"
    (robot / "assets").mkdir(parents=True)
    corners = [(x, y, z) for z in (0, -0.3) for x, y in ((-0.02, -0.02), (0.02, -0.02), (0.02, 0.02), (-0.02, 0.02))]
    faces = ["1 3 2", "1 4 3", "5 6 7", "5 7 8", "1 2 6", "1 6 5", "2 3 7", "2 7 6", "3 4 8", "3 8 7", "4 1 5", "4 5 8"]
    (robot / "assets" / "link.obj").write_text("".join(f"v {x} {y} {z}\n" for x, y, z in corners)
                                               + "".join(f"f {f}\n" for f in faces))
    xml = robot / "pendulum.xml"
    xml.write_text("""<mujoco><compiler meshdir="assets"/><asset><mesh name="link" file="link.obj"/></asset>
      <worldbody><body name="link"><joint name="hinge" type="hinge" axis="1 0 0"/>
        <geom type="mesh" mesh="link" density="1000"/></body></worldbody>
      <actuator><motor name="m" joint="hinge"/></actuator></mujoco>""")
    system = System(str(xml))
    out = tmp_path / "runs" / "diagnosis"
    out.mkdir(parents=True)
    write_fitted_mjcf(str(xml), system, np.array(system.spec.default, float), {}, str(out / "fitted.xml"))
    fitted = mujoco.MjModel.from_xml_path(str(out / "fitted.xml"))
    assert fitted.body_mass[1] == pytest.approx(mujoco.MjModel.from_xml_path(str(xml)).body_mass[1], rel=1e-5)
    assert 'meshdir="../../robot/assets"' in (out / "fitted.xml").read_text()  # relative: both may move together


def test_fitted_xml_of_a_urdf_with_a_refitted_mass_loads(tmp_path):
    """A URDF link's inertia is a full tensor (``ixx`` .. ``iyz``); the re-fitted mass writes the
    principal inertia, which must replace it ("fullinertia and diagonal inertia cannot both be
    specified" lost the file before)."""
    from sim2real.sysid.export import write_fitted_mjcf
    from sim2real.sysid.system import System

    urdf = tmp_path / "pendulum.urdf"
    urdf.write_text("""<robot name="p"><link name="base"/><link name="arm"><inertial><origin xyz="0 0 -0.25"/>
      <mass value="0.5"/><inertia ixx="0.0105" iyy="0.0105" izz="0.0002" ixy="0.00005" ixz="0" iyz="0"/></inertial></link>
      <joint name="pivot" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="1 0 0"/></joint></robot>""")
    system = System(str(urdf))
    z = np.array(system.spec.default, float)
    z[system.spec.index("mass:arm")] = 0.75
    write_fitted_mjcf(str(urdf), system, z, {"mass:arm": 0.75}, str(tmp_path / "fitted.xml"))
    fitted, declared = (mujoco.MjModel.from_xml_path(str(f)) for f in (tmp_path / "fitted.xml", urdf))
    assert fitted.body_mass[-1] == pytest.approx(0.75)
    np.testing.assert_allclose(fitted.body_inertia[-1], 1.5 * declared.body_inertia[-1], rtol=1e-5)


def test_fitted_xml_lag_drives_the_force_in_the_step_the_command_arrives(tmp_path):
    """A motor lag written into fitted.xml drives the joint with the torque the fits' command path
    does: the filter updated and applied in the same physics step (MuJoCo's ``actearly``), not a
    step later (MuJoCo's default: the first step's torque 0)."""
    from sim2real.physics.kinds.lag import MotorLag
    from sim2real.sysid.export import write_fitted_mjcf
    from sim2real.sysid.system import System

    xml = tmp_path / "m.xml"
    xml.write_text("""<mujoco><option timestep="0.002"/><worldbody>
      <body name="a"><joint name="j" type="hinge" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/>
      </body></worldbody><actuator><motor name="m" joint="j" gear="5"/></actuator></mujoco>""")
    system = System(str(xml))
    z = np.array(system.spec.default, float)
    row = system.spec.index("motor_lag:m")
    z[row] = 0.03
    write_fitted_mjcf(str(xml), system, z, {}, str(tmp_path / "fitted.xml"))
    m = mujoco.MjModel.from_xml_path(str(tmp_path / "fitted.xml"))
    d = mujoco.MjData(m)
    d.ctrl[:] = 1.0
    lag = MotorLag()
    data, u, path = lag.command_setup(system.mj, system.spec, None), np.zeros(1), []
    for _ in range(5):
        u, _ = lag.command(data, z, u, np.ones(1), None, None, None, 0.002)
        path.append(5.0 * float(u[0]))
        mujoco.mj_step(m, d)
        assert d.qfrc_actuator[0] == pytest.approx(path[-1], rel=1e-5)  # gear x the filtered command
    assert path[0] == pytest.approx(5.0 * (1 - np.exp(-0.002 / 0.03)), rel=1e-5)


def test_physics_step_is_coarsened_only_while_it_predicts_the_same(tmp_path):
    """A pendulum modelled at 0.25 ms and logged at 100 Hz: ``choose_substeps`` keeps a coarser
    step (fewer than the model's 40 per sample) whose native predictions match the model's own
    step's, and the coarser step it keeps is still within a tenth of the weighting scale."""
    from sim2real.sysid.diagnose import _native_runs, choose_substeps
    from sim2real.sysid.system import System
    from sim2real.sysid.trajectory import from_recording, signal_scale

    xml = tmp_path / "p.xml"
    text = open(PENDULUM).read()
    assert 'timestep="0.01"' in text
    xml.write_text(text.replace('timestep="0.01"', 'timestep="0.00025"'))
    case = Case("pendulum", "none", "", (), noise=1e-3, seed=1)
    path = str(tmp_path / "r.csv")
    record(case, path)
    rec = load(path, _model())
    system = System(str(xml), dt=rec.dt)
    trajs = [from_recording(rec, system)]
    n = choose_substeps(system, trajs)
    assert n < system.substeps
    steps = max(5, int(round(0.3 / rec.dt)))
    own = _native_runs(system, trajs, steps, steps, substeps=system.substeps)
    coarse = _native_runs(system, trajs, steps, steps, substeps=n)
    scale = signal_scale([trajs[0].sigma_q], trajs[0].q, angles=system.angles)
    assert np.sqrt(np.nanmean(((coarse - own) / scale) ** 2)) < 0.1


def test_an_effect_fitted_at_its_absent_value_is_not_an_effect():
    """``Candidate.is_off``: zero friction (or delay, payload ...) and a saturation at the top of its
    range are the effect's absence; the selection never names such a fit."""
    from sim2real.sysid.candidates import Candidate

    coul = Candidate("coulomb_friction", "j", ("coulomb:j",), ((0.1,),), (0.2,), ((0.0, 2.0),))
    assert coul.is_off(0.0) and coul.is_off(1e-5) and not coul.is_off(0.01)
    sat = Candidate("actuator_saturation", "m", ("saturation:m",), ((1.0,),), (1.0,), ((0.1, 10.0),))
    assert sat.is_off(9.9) and not sat.is_off(5.0)


# --------------------------------------------------------------------------------------------
# fitted.xml: what MuJoCo can simulate is written in its terms, the rest is named in a comment

def test_fitted_mjcf_simulates_what_mujoco_can_and_says_what_it_cannot(tmp_path):
    from sim2real.sysid.export import write_fitted_mjcf
    from sim2real.sysid.system import System

    xml = os.path.join(ASSETS, "pendulum.xml")
    system = System(xml, dt=0.01)
    fitted = {"action_delay": 2.5, "coulomb:hinge": 0.2, "coulomb_asym:hinge": 0.25, "sensor_offset:hinge": 0.05}
    z = system.spec.vector(fitted)
    write_fitted_mjcf(xml, system, z, fitted, str(tmp_path / "fitted.xml"))
    text = (tmp_path / "fitted.xml").read_text()
    m = mujoco.MjModel.from_xml_path(str(tmp_path / "fitted.xml"))
    motor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "motor")
    assert m.actuator_delay[motor] == pytest.approx(0.025)  # 2.5 samples of 10 ms
    bias = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "sim2real_friction_offset:hinge")
    assert bias == m.nu - 1 and m.actuator_biasprm[bias, 0] == pytest.approx(-0.25 * 0.2)
    # the sensor offset has no MuJoCo attribute: named in the comment, kept as <numeric>
    comment = text[text.index("<!--"): text.index("-->")]
    assert "NOT simulated" in comment and "sensor_offset:hinge" in comment
    assert "action_delay" in comment.split("NOT simulated")[0]  # written natively
    assert 'name="sim2real:sensor_offset:hinge"' in text
    # the delay acts: a step command reaches the joint 25 ms later (zero gravity, nothing else moves it)
    m.opt.gravity[:] = 0.0
    m.dof_frictionloss[:] = 0.0
    m.actuator_biasprm[bias, 0] = 0.0
    d = mujoco.MjData(m)
    force = []
    for _ in range(int(round(0.05 / m.opt.timestep))):
        d.ctrl[motor] = 1.0
        mujoco.mj_step(m, d)
        force.append(d.actuator_force[motor])
    t_first = (np.argmax(np.abs(np.asarray(force)) > 1e-9) + 1) * m.opt.timestep
    assert 0.02 <= t_first <= 0.035


def test_fitted_friction_is_as_hard_in_mujoco_as_the_fitted_law(tmp_path):
    """``fitted.xml`` writes a fitted Coulomb level as ``frictionloss`` with the hardest friction
    MuJoCo simulates (``solreffriction`` at two physics steps): a pendulum swinging to a stop with it follows
    ideal Coulomb friction (integrated here on its own, with stiction) far closer than MuJoCo's
    default soft friction does."""
    from sim2real.sysid.export import write_fitted_mjcf
    from sim2real.sysid.system import System

    xml = tmp_path / "p.xml"
    xml.write_text(open(os.path.join(ASSETS, "pendulum.xml")).read().replace('timestep="0.01"', 'timestep="0.001"'))
    system = System(str(xml), dt=0.01)
    fitted = {"coulomb:hinge": 1.5}
    write_fitted_mjcf(str(xml), system, system.spec.vector(fitted), fitted, str(tmp_path / "fitted.xml"))
    hard = mujoco.MjModel.from_xml_path(str(tmp_path / "fitted.xml"))
    j = mujoco.mj_name2id(hard, mujoco.mjtObj.mjOBJ_JOINT, "hinge")
    assert hard.dof_frictionloss[j] == pytest.approx(1.5)
    assert hard.dof_solref[j, 0] == pytest.approx(0.002)
    soft = mujoco.MjModel.from_xml_path(str(tmp_path / "fitted.xml"))
    soft.dof_solref[j] = (0.02, 1.0)

    def swing(m):
        d = mujoco.MjData(m)
        d.qpos[0] = np.pi - 1.0  # a swing 1 rad either side of hanging down (qpos = 0 is upright)
        out = []
        for _ in range(1500):
            mujoco.mj_step(m, d)
            out.append(d.qpos[0])
        return np.array(out)

    # the reference: I q'' = G sin q - Fc sign(q') - b q', sticking when the load cannot break away
    d = mujoco.MjData(hard)
    d.qpos[0] = np.pi / 2
    mujoco.mj_forward(hard, d)
    M = np.zeros((1, 1))
    mujoco.mj_fullM(hard, d, M)
    inertia, b, G = M[0, 0], float(hard.dof_damping[j]), -float(d.qfrc_bias[0])
    q, v, h, ref = np.pi - 1.0, 0.0, 1e-5, []
    for k in range(1500 * 100):
        load = G * np.sin(q) - b * v
        if v == 0.0 and abs(load) <= 1.5:
            a = 0.0
        else:
            a = (load - 1.5 * np.sign(v if v != 0.0 else load)) / inertia
        v_new = v + h * a
        v = 0.0 if v != 0.0 and np.sign(v_new) != np.sign(v) else v_new  # a stop is a stop
        q += h * v
        if (k + 1) % 100 == 0:
            ref.append(q)
    ref = np.array(ref)
    err_hard, err_soft = (np.sqrt(np.mean((swing(m) - ref) ** 2)) for m in (hard, soft))
    assert err_hard < 0.5 * err_soft


def _short_native_recordings(tmp_path, n, count=3, frictionloss=0.0):
    """``count`` recordings of ``n`` samples of the pendulum stepped by native MuJoCo (a policy that
    falls at once gives such logs); ``frictionloss`` (N m) on its hinge, which the model lacks."""
    m = _model()
    m.dof_frictionloss[0] = frictionloss
    paths = []
    for k in range(count):
        d = mujoco.MjData(m)
        d.qpos[0] = 0.3 + 0.2 * k
        t = np.arange(n) * m.opt.timestep
        u = 1.5 * np.sin(7.0 * t + k)
        q = np.empty(n)
        for i in range(n):
            q[i] = d.qpos[0]
            d.ctrl[0] = u[i]
            mujoco.mj_step(m, d)
        paths.append(str(tmp_path / f"short_{k}.csv"))
        save_csv(paths[-1], t, {"qpos:hinge": q, "ctrl:motor": u})
    return paths


def test_short_recordings_shorten_the_chosen_horizon_not_a_set_one(tmp_path):
    """Three 0.6 s logs: the horizon the data chose is shortened (and the report says so) until
    there are segments to fit and to validate on; a horizon the user set is refused instead."""
    paths = _short_native_recordings(tmp_path, 60)
    d = diagnose(DiagnoseConfig(model=PENDULUM, recordings=tuple(paths[:2]), heldout=(paths[2],),
                                out=str(tmp_path / "d"), plots=False, progress=False, effects=("none",)))
    assert d["answer"] == "none"
    assert not d["fit"]["left"]["unexplained"]  # (the model is the plant: nothing left but noise)
    assert any(n.startswith("prediction horizon shortened to") for n in d["notes"]), d["notes"]
    assert d["horizon_samples"] >= 5 and d["segments"]["val"] >= 2
    with pytest.raises(RecordingError, match="too short for 20-sample predictions"):
        diagnose(DiagnoseConfig(model=PENDULUM, recordings=tuple(paths[:2]), out=str(tmp_path / "e"),
                                plots=False, progress=False, effects=("none",), horizon_seconds=0.2))
    assert not os.path.exists(tmp_path / "e")


def test_after_none_the_report_says_motion_is_left_unexplained(tmp_path, capsys):
    """A pendulum with a 0.8 N m friction its model lacks, diagnosed with no effect to search: the
    answer is `none`, and the command line and report say the motion is left unexplained -- the
    re-fitted model misfits the held-out log by far more than its noise and physics step leave --
    naming the hinge. (The model that is its plant leaves nothing: the short-recordings test.)"""
    from sim2real.commands.diagnose import main

    paths = _short_native_recordings(tmp_path, 300, count=2, frictionloss=0.8)
    out = tmp_path / "d"
    main([f"model={PENDULUM}", f"recordings=[{paths[0]}]", f"heldout=[{paths[1]}]", f"out={out}", "plots=false",
          "progress=false", "effects=[none]"])
    d = json.loads((out / "diagnosis.json").read_text())
    left = d["fit"]["left"]
    assert d["answer"] == "none" and left["unexplained"] and left["ratio"] > left["limit"]
    # the ratio is the misfit per residual over the floor, the mean of each signal's own
    assert left["ratio"] == pytest.approx(left["level"] / left["floor"])
    assert left["per_signal"] == {"qpos:hinge": pytest.approx(left["ratio"])}  # (the one signal)
    printed = capsys.readouterr().out
    assert "Motion is left unexplained" in printed and "most on qpos:hinge" in printed
    assert "**Motion is left unexplained**" in (out / "report.md").read_text()


def test_targets_restrict_the_search_and_unknown_ones_are_refused(tmp_path):
    """``targets``: only effects on the named joints/actuators/bodies (and global ones) are
    searched; a name that is not in the model is refused by key, nothing written."""
    paths = _short_native_recordings(tmp_path, 120, count=2)
    d = diagnose(DiagnoseConfig(model=PENDULUM, recordings=(paths[0],), heldout=(paths[1],), out=str(tmp_path / "d"),
                                plots=False, progress=False, targets=("motor",),
                                effects=("none", "coulomb_friction", "motor_lag", "action_delay")))
    searched = {(e["effect"], e["target"]) for e in d["effects"]}
    assert searched == {("motor_lag", "motor"), ("action_delay", "")}, searched
    # ``expressible``: an effect needing a parameter outside the list is not searched, and the report says so
    d = diagnose(DiagnoseConfig(model=PENDULUM, recordings=(paths[0],), heldout=(paths[1],), out=str(tmp_path / "x"),
                                plots=False, progress=False, effects=("none", "motor_lag", "backlash", "mass_offset"),
                                expressible=("motor_lag:motor", "backlash:motor", "payload:pole")))
    searched = {(e["effect"], e["target"]) for e in d["effects"]}
    assert searched == {("motor_lag", "motor")}, searched
    assert any("not searched" in n and "backlash@motor" in n and "mass_offset@pole" in n for n in d["notes"]), d["notes"]
    with pytest.raises(ValueError, match=r"targets: \['hinj'\] name no joint, actuator or body.*hinge"):
        diagnose(DiagnoseConfig(model=PENDULUM, recordings=(paths[0],), out=str(tmp_path / "e"), plots=False,
                                progress=False, targets=("hinj",)))
    assert not os.path.exists(tmp_path / "e")


@pytest.mark.parametrize("folder, model", [("dfki_pendulum", "pendulum.xml"),
                                           ("ibm_double_pendulum", "double_pendulum.xml"),
                                           ("kuka_lwr4", "kuka_lwr4.xml")])
def test_bundled_real_recordings_load_against_their_models(folder, model):
    """Every bundled recording reads against its nominal MJCF (names, uniform rate, finite)."""
    import glob

    base = os.path.join(os.path.dirname(os.path.abspath(emps.__file__)), "data", folder)
    m = mujoco.MjModel.from_xml_path(os.path.join(base, model))
    recs = load_all(sorted(glob.glob(os.path.join(base, "*.csv"))), m)
    assert len(recs) >= 2


def test_backlash_is_searched_on_an_integrating_servo_too(tmp_path):
    """An ``intvelocity`` servo integrates its command; the backlash stage then holds the setpoint
    itself (``kinds/backlash.py``). A backlash candidate is made for it as for the motor beside it,
    and its width can be set; each band's fit keeps its mesh compliant."""
    from sim2real.sysid.candidates import Scales, library
    from sim2real.sysid.system import System

    xml = tmp_path / "servo.xml"
    xml.write_text("""<mujoco><option timestep="0.002"/><worldbody>
      <body name="a"><joint name="j1" type="hinge" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/>
        <body name="b" pos="0 0 -0.3"><joint name="j2" type="hinge" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" mass="0.2"/></body>
      </body></worldbody>
      <actuator><intvelocity name="iv" joint="j1" kp="20" actrange="-3 3"/><motor name="m2" joint="j2" gear="2"/></actuator></mujoco>""")
    system = System(str(xml))
    sc = Scales(force=np.ones(2), speed=np.ones(2), range=np.ones(2), act_force=np.ones(2), dt=0.01, max_delay=8,
                inertia=np.full(2, 0.01))
    bands = library(system, sc, ("backlash",))
    assert [c.target for c in bands] == ["iv", "m2"]
    assert not any("backlash not searched" in n for n in system.notes)
    system.spec.check_value("backlash:iv", 0.01)
    # the screen simulates rigid and compliant meshes; a fit stays compliant: 0, the rigid mesh,
    # is another model, not the soft end of the stiffness (``kinds/backlash.py``, tuning.md step 79)
    for c in bands:
        k = c.params.index(f"backlash_stiffness:{c.target}")
        assert {g[k] for g in c.grid} >= {0.0} and 0 < c.search[k][0] < min(g[k] for g in c.grid if g[k] > 0)


def test_a_declared_spring_is_searched_either_way_and_written_as_the_corrected_total(tmp_path):
    """A joint declaring a spring gets the ``joint_stiffness`` hypothesis as a correction of it,
    either sign, down to a total of 0 (withheld before: a pendulum declaring 2 N m/rad where the
    plant had 2.6 was named a false force limit; ``new_user_probes/fourth_wave.py``)."""
    from sim2real.physics.model_apply import to_mjmodel
    from sim2real.sysid.candidates import Scales, library
    from sim2real.sysid.export import write_fitted_mjcf
    from sim2real.sysid.system import System

    xml = tmp_path / "spring.xml"
    xml.write_text("""<mujoco><option timestep="0.002"/><worldbody><body name="rod">
      <joint name="hinge" axis="0 1 0" stiffness="2"/><geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/>
      </body></worldbody><actuator><motor name="m" joint="hinge"/></actuator></mujoco>""")
    system = System(str(xml))
    sc = Scales(force=np.ones(1), speed=np.ones(1), range=np.ones(1), act_force=np.ones(1), dt=0.01, max_delay=8)
    (c,) = library(system, sc, ("joint_stiffness",))
    assert c.search[0][0] < 0 < c.search[0][1] and {g[0] < 0 for g in c.grid} == {True, False}
    system.spec.check_value("stiffness:hinge", -1.5)   # the declared 2 softened to 0.5
    with pytest.raises(ValueError, match="stiffness:hinge"):
        system.spec.check_value("stiffness:hinge", -2.5)  # a negative total
    z = system.spec.default.copy()
    z[system.spec.index("stiffness:hinge")] = 0.6
    assert to_mjmodel(system.physics, z).jnt_stiffness[0] == pytest.approx(2.6)
    out = str(tmp_path / "fitted.xml")
    write_fitted_mjcf(str(xml), system, z, {"stiffness:hinge": 0.6}, out)
    assert mujoco.MjModel.from_xml_path(out).jnt_stiffness[0] == pytest.approx(2.6)


def test_backlash_on_an_integrating_servo_is_a_rotor_behind_a_dead_band(tmp_path):
    """Against an independent plant: native MuJoCo, the ``intvelocity`` servo driving a rotor
    (armature 1e-3 kg m^2) that meets the pendulum through a 0.05 rad dead band and a 40 Nm/rad
    mesh (damping ratio 0.5), written here with ``qfrc_applied``. The stage with the same band,
    inertia and stiffness follows it to a few percent of what the band changes; with the band
    at 0 it is MuJoCo's own servo on the bare pendulum."""
    from sim2real.physics import stepper
    from sim2real.sysid.system import System

    h, J, k, b, T = 0.0005, 1e-3, 40.0, 0.05, 2000
    c = 2 * 0.5 * np.sqrt(k * J)
    servo = '<intvelocity name="iv" joint="JOINT" kp="6" kv="0.1" ctrllimited="true" ctrlrange="-3 3" actrange="-10 10"/>'
    pole = '<body name="pole"><joint name="pivot" type="hinge" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/></body>'
    rotor = (f'<body name="rotor"><joint name="rot" type="hinge" axis="0 1 0" armature="{J}"/>'
             '<inertial pos="0 0 0" mass="1e-4" diaginertia="1e-9 1e-9 1e-9"/></body>')
    head = f'<mujoco><option timestep="{h}" integrator="implicitfast"/><worldbody>'
    nominal = head + pole + "</worldbody><actuator>" + servo.replace("JOINT", "pivot") + "</actuator></mujoco>"
    truth = head + rotor + pole + "</worldbody><actuator>" + servo.replace("JOINT", "rot") + "</actuator></mujoco>"
    t = np.arange(T) * h
    ctrl = 2.0 * np.sin(2 * np.pi * 1.5 * t) * np.sign(np.sin(2 * np.pi * 0.8 * t + 0.1))

    def native(xml, band):
        m = mujoco.MjModel.from_xml_string(xml)
        d = mujoco.MjData(m)
        d.qpos[:] = 0.2
        d.act[0] = 0.2
        out = []
        for u in ctrl:
            d.ctrl[0] = u
            if m.nq == 2:  # the mesh: rotor (0) against pole (1) beyond the band
                gap = d.qpos[0] - d.qpos[1]
                tq = k * np.sign(gap) * max(abs(gap) - band / 2, 0) + (c * (d.qvel[0] - d.qvel[1]) if abs(gap) > band / 2 else 0)
                d.qfrc_applied[:] = [-tq, tq]
            out.append(d.qpos[-1])
            mujoco.mj_step(m, d)
        return np.array(out)

    (tmp_path / "nominal.xml").write_text(nominal)
    system = System(str(tmp_path / "nominal.xml"), dt=h)
    names = [p.name for p in system.spec.params]

    def stage(band):
        z = np.array([p.default for p in system.spec.params], np.float32)
        for name, v in (("backlash:iv", band), ("backlash_inertia:iv", J), ("backlash_stiffness:iv", k)):
            z[names.index(name)] = v
        z = jnp.asarray(z)
        model = system.physics.apply(z)

        def step(carry, u):
            d, es = carry
            d2, es = stepper.advance(system.effects, model, z, d, es, u[None], h, 1)
            return (d2, es), d.qpos[0]

        d0 = system.data0.replace(qpos=jnp.full(1, 0.2), act=jnp.full(1, 0.2))
        return np.asarray(jax.lax.scan(step, (d0, system.effects.init_state()), jnp.asarray(ctrl, jnp.float32))[1])

    rms = lambda a, b: float(np.sqrt(np.mean((a - b) ** 2)))  # noqa: E731
    with_band, bare = native(truth, b), native(nominal, 0.0)
    assert rms(with_band, bare) > 0.01                          # the band matters here
    assert rms(stage(b), with_band) < 0.1 * rms(with_band, bare)
    np.testing.assert_allclose(stage(0.0), bare, atol=1e-5)


def test_an_integrating_servo_starts_where_a_sensor_offset_says_the_joint_is(tmp_path):
    """Against native MuJoCo: an ``intvelocity`` servo on a pendulum starts holding its joint's
    true position, and the logger reads it 0.05 rad off. With that offset hypothesised, the
    servo's setpoint starts at the measured position less the offset, so the true physics
    predicts every segment; started at the measured one, the servo would pull by the offset."""
    from sim2real.sysid.shooting import Shooting
    from sim2real.sysid.system import System
    from sim2real.sysid.trajectory import from_recording

    xml = tmp_path / "servo.xml"
    xml.write_text("""<mujoco><option timestep="0.001"/><worldbody>
      <body name="bar"><joint name="pivot" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.015" mass="0.25"/></body></worldbody>
      <actuator><intvelocity name="iv" joint="pivot" kp="6" kv="0.1" actrange="-10 10"/></actuator></mujoco>""")
    m = mujoco.MjModel.from_xml_path(str(xml))
    d = mujoco.MjData(m)
    d.qpos[0] = d.act[0] = 0.4
    T, offset = 2000, 0.05
    u = 1.5 * np.sin(2 * np.pi * 0.7 * np.arange(T) * 1e-3)
    q = np.empty(T)
    for k in range(T):
        q[k] = d.qpos[0]
        d.ctrl[0] = u[k]
        mujoco.mj_step(m, d)
    path = str(tmp_path / "rec.csv")
    save_csv(path, np.arange(T) * 1e-3, {"qpos:pivot": q + offset, "ctrl:iv": u})
    system = System(str(xml), dt=1e-3)
    sh = Shooting(system, [from_recording(load(path, m), system)], 100, val_fraction=0.3)
    tiles = sh.tiles.of("fit")
    pred = sh.predict(system.spec.vector({"sensor_offset:pivot": offset})[None], sh.v0[None], tiles)["qpos"][0]
    assert np.abs(pred - sh.signals["qpos"][tiles]).max() < 0.1 * offset


def test_a_hinge_angle_logged_wrapped_into_one_turn_is_unwrapped(tmp_path):
    """A pendulum spinning over the top, logged in (-pi, pi] as encoders and ``joint_states`` do:
    the model-order positions are continuous, and the note names the column; a jump that is not a
    whole turn (a glitch) is left as it is."""
    from sim2real.sysid.trajectory import ModelColumns

    m = mujoco.MjModel.from_xml_path(os.path.join(ASSETS, "pendulum.xml"))
    t = np.arange(300) * 0.01
    angle = 12.0 * t                                             # 12 rad/s: 0.12 rad per sample
    path = str(tmp_path / "spin.csv")
    save_csv(path, t, {"qpos:hinge": np.arctan2(np.sin(angle), np.cos(angle)), "ctrl:motor": 0 * t})
    cols = ModelColumns(m, "pendulum.xml")
    qpos = cols.arrays(load(path, m))[0]
    np.testing.assert_allclose(qpos[:, 0], angle, atol=1e-6)
    assert cols.notes == ["spin: qpos:hinge wraps around a turn (6 jumps of 2 pi): unwrapped"]
    glitch = 0.3 * np.sin(t)
    glitch[100] += 4.0
    save_csv(path, t, {"qpos:hinge": glitch, "ctrl:motor": 0 * t})
    cols = ModelColumns(m, "pendulum.xml")
    np.testing.assert_array_equal(cols.arrays(load(path, m))[0][:, 0], load(path, m).get("qpos", "hinge"))
    assert cols.notes == []


def test_jittered_time_stamps_are_resampled_onto_the_median_grid(tmp_path):
    """A logger whose samples are taken up to a fifth of a step off their instants (ROS
    ``joint_states``), stamped when taken, with one sample lost: the recording comes back on the
    median step's grid, positions interpolated (to the motion's curvature), each command the
    nearest row's, a wrapped spinning angle still whole turns for ``ModelColumns`` to unwrap, and
    a note; stamps within 1% are kept as they are; a gap of more than 3 steps is refused."""
    from sim2real.sysid.trajectory import ModelColumns

    m = mujoco.MjModel.from_xml_path(os.path.join(ASSETS, "pendulum.xml"))
    rng = np.random.default_rng(0)
    k = np.delete(np.arange(400), 150)                            # sample 150 lost
    t = 2.0 + 0.005 * (k + rng.uniform(-0.2, 0.2, len(k)))
    angle = 12.0 * t + np.sin(3 * t)
    cmd = np.sign(np.sin(7 * k))                                  # a command per loop instant
    path = str(tmp_path / "jitter.csv")
    save_csv(path, t, {"qpos:hinge": np.arctan2(np.sin(angle), np.cos(angle)), "ctrl:motor": cmd})
    rec = load(path, m)
    grid = 2.0 + 0.005 * np.arange(400)
    assert rec.dt == pytest.approx(0.005, rel=1e-3) and len(rec) == 400
    np.testing.assert_allclose(rec.time, grid, atol=0.0006)   # (the grid fitted to the stamps)
    cols = ModelColumns(m, "pendulum.xml")
    qpos = cols.arrays(rec)[0][:, 0]
    np.testing.assert_allclose(qpos - qpos[0], 12.0 * rec.time + np.sin(3 * rec.time) - angle[0], atol=2e-3)
    np.testing.assert_array_equal(np.delete(rec.get("ctrl", "motor"), 150), cmd)
    assert "resampled onto it" in rec.notes[0] and cols.notes
    save_csv(path, 0.005 * (np.arange(400) + 0.005 * rng.uniform(-1, 1, 400)), {"qpos:hinge": 0 * grid,
                                                                                "ctrl:motor": 0 * grid})
    assert load(path, m).notes == []
    save_csv(path, np.delete(grid, range(150, 154)), {"qpos:hinge": np.zeros(396), "ctrl:motor": np.zeros(396)})
    with pytest.raises(RecordingError, match="non-uniform sampling at data row 151.*samples lost"):
        load(path, m)


def test_a_recording_that_lost_samples_is_cut_into_pieces(tmp_path):
    """A logger that lost 4 samples after row 150 and 30 after row 380 (jittered stamps beside):
    ``load_all`` gives the pieces as recordings of their own, named by their rows, each on its own
    grid, nothing interpolated over a gap; a piece under 20 samples is left out, and the note says
    where the file was cut."""
    m = mujoco.MjModel.from_xml_path(os.path.join(ASSETS, "pendulum.xml"))
    k = np.delete(np.arange(430), [*range(150, 154), *range(390, 420)])   # 396 samples left
    t = 1.0 + 0.005 * (k + np.random.default_rng(1).uniform(-0.2, 0.2, len(k)))
    path = str(tmp_path / "drops.csv")
    save_csv(path, t, {"qpos:hinge": np.sin(t), "ctrl:motor": np.cos(7 * t)})
    pieces = load_all([path], m)
    assert [p.rows for p in pieces] == ["1-150", "151-386"] and [p.name for p in pieces] == [
        "drops[rows 1-150]", "drops[rows 151-386]"]
    assert [len(p) for p in pieces] == [150, 236]
    np.testing.assert_allclose(pieces[1].time[[0, -1]], [1.0 + 0.005 * 154, 1.0 + 0.005 * 389], atol=0.0006)
    np.testing.assert_allclose(pieces[1].get("qpos", "hinge"), np.sin(pieces[1].time), atol=1e-3)  # (edges held)
    assert "cut into 2 pieces, data rows 1-150, 151-386 (10 samples in pieces under 20 left out)" in pieces[0].notes[0]
    assert "resampled onto it" in pieces[1].notes[-1]


_DRONE = """<mujoco><worldbody><body name="quad" pos="0 0 1"><freejoint name="root"/>
<geom type="box" size="0.06 0.06 0.02" mass="0.6"/>
<geom type="capsule" fromto="-0.12 -0.12 0 0.12 0.12 0" size="0.01" mass="0.1"/>
<geom type="capsule" fromto="-0.12 0.12 0 0.12 -0.12 0" size="0.01" mass="0.1"/>
<site name="r1" pos="0.12 0.12 0.01"/><site name="r2" pos="-0.12 -0.12 0.01"/>CAMERA</body></worldbody>
<actuator><motor name="m1" site="r1" gear="0 0 1 0 0 0.02"/><motor name="m2" site="r2" gear="0 0 1 0 0 0.02"/></actuator>
</mujoco>"""


def test_a_payload_on_a_flying_body_sits_where_its_three_coordinates_put_it(tmp_path):
    """A body on a free joint (a drone) has no link to put a payload along: its ``mass_offset``
    has a place in the body's frame (``payload_x/y/z``), searched within twice the body's reach.
    The physics it gives (mass, centre of mass, the inertia on the body's principal axes) is
    MuJoCo's own for a small sphere there; the thrusters' gains, sized by their gear's length
    (the first entry of "0 0 1 0 0 0.02" is 0), leave the drone's thrust as declared."""
    from sim2real.sysid.system import System

    (tmp_path / "drone.xml").write_text(_DRONE.replace("CAMERA", ""))
    system = System(str(tmp_path / "drone.xml"))
    spec = system.spec
    reach = 2 * (np.hypot(0.12, 0.12) + 0.01)   # twice the arms' reach from the centre
    assert (spec["payload_x:quad"].low, spec["payload_x:quad"].high) == pytest.approx((-reach, reach), rel=1e-5)
    assert spec["gain:m1"].default == pytest.approx(np.hypot(1, 0.02))
    z = spec.default.copy()
    for name, v in {"payload:quad": 0.12, "payload_x:quad": 0.04, "payload_y:quad": -0.01, "payload_z:quad": -0.05}.items():
        z[spec.index(name)] = v
    fitted, nominal = system.physics.apply(jnp.asarray(z)), system.physics.apply(jnp.asarray(spec.default))
    truth = mujoco.MjModel.from_xml_string(_DRONE.replace(
        "CAMERA", '<geom type="sphere" pos="0.04 -0.01 -0.05" size="0.0005" mass="0.12"/>'))
    b = 1
    assert float(fitted.body_mass[b]) == pytest.approx(truth.body_mass[b], rel=1e-6)
    np.testing.assert_allclose(np.asarray(fitted.body_ipos[b]), truth.body_ipos[b], atol=1e-6)
    # MuJoCo's tensor about the new centre, on the nominal body's principal axes
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, truth.body_iquat[b])
    tensor = rot.reshape(3, 3) @ np.diag(truth.body_inertia[b]) @ rot.reshape(3, 3).T
    mujoco.mju_quat2Mat(rot, np.asarray(nominal.body_iquat[b], float))
    on_axes = np.diagonal(rot.reshape(3, 3).T @ tensor @ rot.reshape(3, 3))
    np.testing.assert_allclose(np.asarray(fitted.body_inertia[b]), on_axes, rtol=1e-4)
    np.testing.assert_allclose(np.asarray(nominal.actuator_gainprm[:, 0]), 1.0)   # (not scaled by 0)
    assert "mass_offset@quad" in [c.label for c in _library(system)]


_FLANGE_ARM = """<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.03" mass="2"/>
      <body name="flange" pos="0.4 0 0">
        <joint name="roll" axis="1 0 0"/>
        <geom type="cylinder" fromto="0 0 0 0.02 0 0" size="0.03" mass="0.1"/>GRIPPER
        <body name="hand" pos="0.05 0 0"><geom type="box" size="0.02 0.03 0.01" mass="0.05"/></body>
      </body>
    </body>
  </worldbody>
  <actuator><motor name="m1" joint="shoulder"/><motor name="m2" joint="roll"/></actuator>
</mujoco>"""


def test_a_payload_on_a_body_turning_about_its_own_centre_of_mass_is_searched_in_three_coordinates(tmp_path):
    """An arm's last link often turns about an axis through its centre of mass (a flange, a wrist
    roll: Menagerie's UR5e has three such), so no link runs from its joint to put a payload along;
    before, it got no payload candidate, and a gripper on the flange was never searched for. Its
    ``mass_offset`` has a place in the body's frame, its mass sized by the arm behind it (a tenth
    of the mass of the bodies from the world to it: 0.21 kg here, not the flange's 0.1), and the physics at a place
    off the axis is MuJoCo's own for a mass there. A body welded to a moving one (a hand) is placed
    alike (Menagerie's Panda: a tool held along its flange's axis had no candidate)."""
    from sim2real.sysid.system import System

    (tmp_path / "arm.xml").write_text(_FLANGE_ARM.replace("GRIPPER", ""))
    system = System(str(tmp_path / "arm.xml"))
    spec = system.spec
    assert {"payload_x:flange", "payload_y:flange", "payload_z:flange"} <= set(spec.names)
    assert "payload_r:flange" not in spec.names and "payload_r:upper" in spec.names
    assert "payload_x:hand" in spec.names   # (a body welded to a moving one: a hand, placed alike)
    cand = next(c for c in _library(system) if c.label == "mass_offset@flange")
    assert cand.params[0] == "payload:flange" and cand.search[0][1] == pytest.approx(5 * 0.21)
    z = spec.default.copy()
    for name, v in {"payload:flange": 0.5, "payload_x:flange": 0.06, "payload_z:flange": -0.02}.items():
        z[spec.index(name)] = v
    fitted = system.physics.apply(jnp.asarray(z))
    truth = mujoco.MjModel.from_xml_string(_FLANGE_ARM.replace(
        "GRIPPER", '<geom type="sphere" pos="0.07 0 -0.02" size="0.0005" mass="0.5"/>'))   # (the centre at x 0.01)
    assert float(fitted.body_mass[2]) == pytest.approx(truth.body_mass[2], rel=1e-6)
    np.testing.assert_allclose(np.asarray(fitted.body_ipos[2]), truth.body_ipos[2], atol=1e-6)


def test_an_elliptic_cone_without_contacts_is_simulated_pyramidal(tmp_path):
    """MJX's elliptic-cone solver fails at its first step on a model with constraints (here a
    friction loss) and no contact ("Indexer must have integer or boolean type": Menagerie's
    SO-ARM100, every contact left out): without contacts the cone changes nothing, so the
    simulated model's is pyramidal; with a contact that can happen it stays elliptic."""
    from mujoco import mjx

    from sim2real.sysid.system import System

    xml = """<mujoco><option cone="elliptic"/><worldbody>FLOOR<body name="rod" pos="0 0 1"><joint name="h" axis="0 1 0"
      frictionloss="0.1"/><geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4" CONTACT/></body>
      </worldbody><actuator><motor name="m" joint="h"/></actuator></mujoco>"""
    (tmp_path / "free.xml").write_text(xml.replace("FLOOR", "").replace("CONTACT", 'contype="0" conaffinity="0"'))
    system = System(str(tmp_path / "free.xml"))
    assert system.mj.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL
    mx = mjx.put_model(system.mj)
    assert np.isfinite(np.asarray(jax.jit(mjx.step)(mx, mjx.make_data(mx)).qpos)).all()
    (tmp_path / "floor.xml").write_text(xml.replace("FLOOR", '<geom type="plane" size="1 1 0.1"/>').replace("CONTACT", ""))
    assert System(str(tmp_path / "floor.xml")).mj.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC


def _library(system):
    from sim2real.sysid.candidates import Scales, library

    n = system.mj.njnt
    sc = Scales(np.ones(n), np.ones(n), np.ones(n), np.ones(system.mj.nu), 0.005, 8, np.ones(n),
                np.zeros(system.mj.nbody, bool))
    return library(system, sc)
