"""Bad input, as a hostile-but-fair user would give it: every case exits with status 2, says what is
wrong (naming the file, column, row or key), prints no traceback, and changes no file on disk.

The scripts run in-process (``main_guard(main, argv)``, as from the shell) in a scratch working
folder holding a model, good recordings and a user's own notes; every file in that folder is
hashed before and after each case.
"""
import hashlib
import importlib.util
import os
import shutil

import numpy as np
import pytest

from sim2real.common.cli import main_guard
from sim2real.envs.base import ASSETS
from sim2real.sysid.recordings import save_csv

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PENDULUM = os.path.join(ASSETS, "pendulum.xml")


def _script(name):
    spec = importlib.util.spec_from_file_location(f"script_{name}", os.path.join(ROOT, "scripts", f"{name}.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


SCRIPTS = {n: _script(n) for n in ("diagnose", "train", "evaluate")}


def _snapshot(folder):
    out = {}
    for base, _, files in os.walk(folder):
        for f in files:
            p = os.path.join(base, f)
            with open(p, "rb") as fh:
                out[os.path.relpath(p, folder)] = hashlib.sha256(fh.read()).hexdigest()
    return out


def _recording(path, n=400, dt=0.01, **changes):
    t = np.arange(n) * dt + 100.0
    cols = {"qpos:hinge": 0.3 * np.sin(2 * t), "ctrl:motor": 0.5 * np.cos(3 * t)}
    cols.update(changes)
    save_csv(path, t, cols)
    return path


@pytest.fixture
def lab(tmp_path, monkeypatch):
    """A user's working folder: model, two good recordings, notes; the working directory."""
    shutil.copy(PENDULUM, tmp_path / "robot.xml")
    _recording(str(tmp_path / "a.csv"))
    _recording(str(tmp_path / "b.csv"))
    (tmp_path / "lab_notes.txt").write_text("do not delete\n")
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "results.txt").write_text("a folder the user made\n")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _write(lab, name, text, mode="w"):
    with open(lab / name, mode) as f:
        f.write(text)
    return name


GOOD = "time,qpos:hinge,ctrl:motor\n" + "".join(f"{k * 0.01:.2f},{0.1 * np.sin(k / 9):.6f},{0.2:.2f}\n"
                                                 for k in range(60))


def _rows(edit):
    lines = GOOD.splitlines()
    edit(lines)
    return "\n".join(lines) + "\n"


def _set(lines, row, col, value):
    cells = lines[row].split(",")
    cells[col] = value
    lines[row] = ",".join(cells)


# (id, script, argv, files to create {name: text|bytes}, text the message must contain)
D = ["model=robot.xml", "heldout=[b.csv]", "progress=false", "plots=false"]
CASES = [
    # ---- recordings -------------------------------------------------------------------------------
    ("missing_file", "diagnose", D + ["recordings=[nope.csv]"], {}, "nope.csv: file not found"),
    ("files_joined_by_commas", "diagnose", D + ["recordings=a.csv,c.csv"], {"a.csv": GOOD, "c.csv": GOOD},
     "for several files write a list: '[a.csv, c.csv]'"),
    ("empty_file", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": ""}, "r.csv: empty file"),
    ("header_only", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": "time,qpos:hinge,ctrl:motor\n"},
     "r.csv: no data rows"),
    ("no_time", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": GOOD.replace("time,", "t,", 1)}, "no 'time' column"),
    ("time_named_t", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": GOOD.replace("time,", "Time,", 1)},
     "if 'Time' is the time, name it 'time' (in seconds)"),
    ("no_header_row", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": GOOD.split("\n", 1)[1]},
     "r.csv: the first row holds numbers (0.00,0.000000,0.20), not column names"),
    ("bare_joint_name", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": GOOD.replace("qpos:hinge", "hinge", 1)},
     "its position is 'qpos:hinge'"),
    ("position_unit_degrees", "diagnose", D + ["recordings=[r.csv]"],
     {"r.csv": GOOD.replace("qpos:hinge", "qpos:hinge [deg]", 1)},
     "column 'qpos:hinge [deg]' is in deg; qpos:hinge is read in rad (to rad: multiply by pi/180)"),
    ("unknown_kind", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": GOOD.replace("qpos:hinge", "angle:hinge", 1)},
     "unknown column 'angle:hinge'"),
    ("unknown_joint", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": GOOD.replace("qpos:hinge", "qpos:elbow", 1)},
     "column 'qpos:elbow' names joint 'elbow'"),
    ("missing_ctrl", "diagnose", D + ["recordings=[r.csv]"],
     {"r.csv": "\n".join(",".join(r.split(",")[:2]) for r in GOOD.splitlines()) + "\n"}, "ctrl:motor"),
    ("nan_value", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": _rows(lambda L: _set(L, 7, 1, "nan"))},
     "non-finite value nan in column 'qpos:hinge' at data row 7"),
    ("inf_value", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": _rows(lambda L: _set(L, 9, 2, "inf"))},
     "column 'ctrl:motor' at data row 9"),
    ("text_cell", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": _rows(lambda L: _set(L, 5, 1, "abc"))},
     "'abc' in column 'qpos:hinge' at data row 5 is not a number"),
    ("empty_cell", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": _rows(lambda L: _set(L, 4, 2, ""))},
     "empty cell in column 'ctrl:motor' at data row 4"),
    ("ragged_row", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": _rows(lambda L: L.__setitem__(3, "0.02,0.1"))},
     "data row 3 has 2 values"),
    ("duplicated_column", "diagnose", D + ["recordings=[r.csv]"],
     {"r.csv": GOOD.replace("ctrl:motor", "qpos:hinge", 1)}, "duplicated column"),
    ("duplicated_time", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": _rows(lambda L: _set(L, 11, 0, "0.09"))},
     "duplicated time"),
    ("backwards_time", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": _rows(lambda L: _set(L, 21, 0, "0.05"))},
     "time goes backwards at data row 21"),
    ("gaps_in_time", "diagnose", D + ["recordings=[r.csv]"],   # (a longer piece would be diagnosed: load_pieces)
     {"r.csv": _rows(lambda L: [_set(L, k, 0, f"{(k - 1) * 0.01 + 0.5 * ((k >= 15) + (k >= 30) + (k >= 45)):.2f}")
                                for k in range(1, 61)])},
     "samples lost at 3 places (data rows 15, 30, 45), leaving no piece of 20 samples"),
    ("angle_in_degrees", "diagnose", ["model=limited.xml", "recordings=[r.csv]", "progress=false"],
     {"limited.xml": open(PENDULUM).read().replace('limited="false"', 'range="-1.5 1.5"'),
      "r.csv": "time,qpos:hinge,ctrl:motor\n" + "".join(f"{k * 0.01:.2f},{60 * np.sin(k / 9):.6f},0.2\n" for k in range(60))},
     "column 'qpos:hinge' reads 6.6"),
    ("range_read_as_degrees", "diagnose", ["model=limited.xml", "recordings=[r.csv]", "progress=false"],
     {"limited.xml": open(PENDULUM).read().replace('limited="false"', 'range="-1.5 1.5"'),   # (no compiler: degrees)
      "r.csv": "time,qpos:hinge,ctrl:motor\n" + "".join(f"{k * 0.01:.2f},{1.2 * np.sin(k / 9):.6f},0.2\n" for k in range(60))},
     "range was written in radians"),
    ("velocity_in_degrees", "diagnose", D + ["recordings=[r.csv]"],
     {"r.csv": "time,qpos:hinge,qvel:hinge,ctrl:motor\n" + "".join(
         f"{k * 0.01:.2f},{0.5 * np.sin(2 * k * 0.01):.6f},{np.degrees(np.cos(2 * k * 0.01)):.6f},0.2\n" for k in range(400))},
     "column 'qvel:hinge' integrates over the time column to 57.3x"),
    ("stamps_on_another_clock", "diagnose", D + ["recordings=[r.csv]"],   # samples every 4 ms stamped 5 ms apart
     {"r.csv": "time,qpos:hinge,qvel:hinge,ctrl:motor\n" + "".join(
         f"{k * 0.005:.3f},{0.5 * np.sin(2 * k * 0.004):.6f},{np.cos(2 * k * 0.004):.6f},0.2\n" for k in range(1000))},
     "spaced 1.25x the samples' true period"),
    ("time_in_milliseconds", "diagnose", D + ["recordings=[r.csv]"],
     {"r.csv": "time,qpos:hinge,ctrl:motor\n" + "".join(f"{k * 10},{0.1 * np.sin(k / 9):.6f},0.2\n" for k in range(60))},
     "column 'time': the samples are 10 s apart"),
    ("too_few_samples", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": "\n".join(GOOD.splitlines()[:11]) + "\n"},
     "only 10 samples"),
    ("garbage_bytes", "diagnose", D + ["recordings=[r.csv]"], {"r.csv": bytes(range(256)) * 3}, "r.csv: cannot read as CSV"),
    ("garbage_npz", "diagnose", D + ["recordings=[r.npz]"], {"r.npz": b"not a zip file at all"}, "r.npz: cannot read as NPZ"),
    ("unsupported_type", "diagnose", D + ["recordings=[r.xlsx]"], {"r.xlsx": GOOD},
     "unsupported file type '.xlsx' (use .csv, .tsv, .txt, .npz, .mat, .parquet, .mcap; a spreadsheet: save it as CSV)"),
    ("folder_as_recording", "diagnose", D + ["recordings=[mine]"], {}, "mine: is a folder"),
    ("mixed_rates", "diagnose", ["model=robot.xml", "recordings=[a.csv,r.csv]", "progress=false"],
     {"r.csv": "time,qpos:hinge,ctrl:motor\n" + "".join(f"{k * 0.02:.2f},0.1,0.2\n" for k in range(60))},
     "r.csv: sample rate 50 Hz differs"),
    ("heldout_rate", "diagnose", ["model=robot.xml", "recordings=[a.csv]", "heldout=[r.csv]", "progress=false"],
     {"r.csv": "time,qpos:hinge,ctrl:motor\n" + "".join(f"{k * 0.02:.2f},0.1,0.2\n" for k in range(60))},
     "r.csv: sample rate 50 Hz differs"),
    ("columns_differ", "diagnose", ["model=robot.xml", "recordings=[a.csv,r.csv]", "progress=false"],
     {"r.csv": "time,qpos:hinge,qvel:hinge,ctrl:motor\n" + "".join(f"{k * 0.01:.2f},0.1,0,0.2\n" for k in range(60))},
     "columns differ"),
    ("npz_wrong_names", "diagnose", D + ["recordings=[r.npz]"], {"r.npz": "npz:time,angle,ctrl:motor"},
     "unknown column 'angle'"),
    # ---- the model ----------------------------------------------------------------------------------
    ("model_missing", "diagnose", ["model=none.xml", "recordings=[a.csv]"], {}, "model file 'none.xml' not found"),
    ("model_unparsable", "diagnose", ["model=bad.xml", "recordings=[a.csv]"], {"bad.xml": "<mujoco><worldbody>"},
     "bad.xml: cannot compile the MJCF"),
    ("model_ball_joint", "diagnose", ["model=ball.xml", "recordings=[a.csv]"],
     {"ball.xml": '<mujoco><worldbody><body><joint name="hinge" type="ball"/><geom size=".1"/></body>'
                  '</worldbody></mujoco>'},
     "column 'qpos:hinge': joint 'hinge' has several coordinates (a ball or free joint); its qpos columns are "
     "qpos:hinge:qw, qpos:hinge:qx, qpos:hinge:qy, qpos:hinge:qz"),
    ("model_body_transmission", "diagnose", ["model=body.xml", "recordings=[a.csv]"],
     {"body.xml": '<mujoco><worldbody><body name="b"><joint name="hinge"/><geom size=".1"/></body></worldbody>'
                  '<actuator><adhesion name="grip" body="b" ctrlrange="0 1" gain="1"/></actuator></mujoco>'},
     "actuator 'grip' has a body transmission; the diagnosis handles actuators on joints, tendons and sites only"),
    ("model_other_joints", "diagnose", [f"model={os.path.join(ASSETS, 'arm2.xml')}", "recordings=[a.csv]"], {},
     "names joint 'hinge'"),
    ("model_required", "diagnose", ["recordings=[a.csv]"], {}, "model=PATH.xml is required"),
    # ---- output folders -------------------------------------------------------------------------------
    ("out_is_file", "diagnose", D + ["recordings=[a.csv]", "out=lab_notes.txt"], {}, "out=lab_notes.txt is an existing file"),
    ("out_holds_inputs", "diagnose", D + ["recordings=[a.csv]", "out=.", "overwrite=true"], {},
     "out=. is the current, home or root folder"),
    ("out_parent_of_input", "diagnose", ["model=sub/robot.xml", "recordings=[a.csv]", "out=sub", "overwrite=true"],
     {"sub/robot.xml": open(PENDULUM).read()}, "out=sub holds the input 'sub/robot.xml'"),
    ("out_users_folder", "diagnose", D + ["recordings=[a.csv]", "out=mine", "overwrite=true"], {},
     "out=mine was not made by sim2real"),
    ("out_exists", "diagnose", D + ["recordings=[a.csv]", "out=mine"], {}, "out=mine exists; pass overwrite=true"),
    ("out_under_a_file", "diagnose", D + ["recordings=[a.csv]", "out=lab_notes.txt/diag"], {},
     "cannot create a folder in"),
    # ---- diagnosis settings -------------------------------------------------------------------------------
    ("unknown_key", "diagnose", D + ["recordings=[a.csv]", "horizon_second=1"], {}, "Did you mean: horizon_seconds"),
    ("bad_number", "diagnose", D + ["recordings=[a.csv]", "horizon_seconds=abc"], {}, "horizon_seconds: expected a number"),
    ("negative_horizon", "diagnose", D + ["recordings=[a.csv]", "horizon_seconds=-1"], {}, "horizon_seconds=-1.0"),
    ("nan_setting", "diagnose", D + ["recordings=[a.csv]", "min_gain=.nan"], {}, "min_gain=nan"),
    ("val_fraction", "diagnose", D + ["recordings=[a.csv]", "val_fraction=0.9"], {}, "val_fraction=0.9"),
    ("negative_finer", "diagnose", D + ["recordings=[a.csv]", "finer=-1"], {}, "finer=-1: must be >= 0"),
    ("precision_48", "diagnose", D + ["recordings=[a.csv]", "precision=48"], {}, "precision=48: must be 32 or 64"),
    ("finer_ratio_above_one", "diagnose", D + ["recordings=[a.csv]", "finer_ratio=1.5"], {},
     "finer_ratio=1.5: must be a fraction in (0, 1]"),
    ("rotor_ratio_zero", "diagnose", D + ["recordings=[a.csv]", "rotor_ratio=0"], {},
     "rotor_ratio=0.0: must be a fraction in (0, 1]"),
    ("negative_heldout_gain", "diagnose", D + ["recordings=[a.csv]", "heldout_gain=-0.1"], {},
     "heldout_gain=-0.1: must be a finite number >= 0"),
    ("nan_energy_explained", "diagnose", D + ["recordings=[a.csv]", "energy_explained=nan"], {},
     "energy_explained=nan: must be a finite number >= 0"),
    ("unknown_effect", "diagnose", D + ["recordings=[a.csv]", "effects=[none,fricton]"], {}, "unknown effect(s) ['fricton']"),
    ("unknown_group_effect", "diagnose", D + ["recordings=[a.csv]", "group=[fricton]"], {}, "group: unknown effect(s) ['fricton']"),
    ("not_key_value", "diagnose", ["robot.xml"], {}, "argument 'robot.xml' is not of the form key=value"),
    # ---- training configs -----------------------------------------------------------------------------------
    ("train_unknown_key", "train", ["ppo.num_env=4"], {}, "Did you mean: ppo.num_envs"),
    ("train_negative_envs", "train", ["ppo.num_envs=-4"], {}, "ppo.num_envs=-4: must be a positive integer"),
    ("train_zero_envs", "train", ["ppo.num_envs=0"], {}, "ppo.num_envs=0"),
    ("train_zero_seeds", "train", ["num_seeds=0"], {}, "num_seeds=0: must be a positive integer"),
    ("train_zero_chunk", "train", ["updates_per_chunk=0"], {}, "updates_per_chunk=0"),
    ("train_zero_steps", "train", ["total_steps=0"], {}, "total_steps=0"),
    ("train_text_steps", "train", ["total_steps=many"], {}, "total_steps: expected an integer"),
    ("train_negative_lr", "train", ["ppo.lr=-0.1"], {}, "ppo.lr=-0.1"),
    ("train_gamma", "train", ["ppo.gamma=1.5"], {}, "ppo.gamma=1.5"),
    ("train_minibatches", "train", ["ppo.num_envs=6", "ppo.num_steps=5", "ppo.num_minibatches=4"], {},
     "must be divisible by ppo.num_minibatches=4"),
    ("train_unknown_env", "train", ["env=pendulm"], {}, "unknown env 'pendulm'"),
    ("train_unknown_algo", "train", ["algo=lsdrr"], {}, "unknown algo 'lsdrr'"),
    ("train_box_outside_bounds", "train", ["dr.params=[mass:pole]", "dr.low=[-1.0]", "dr.high=[1.7]"], {},
     "dr box for 'mass:pole' [-1.0, 1.7] reaches outside its physical bounds"),
    ("train_box_unknown_param", "train", ["dr.params=[mass:pol]", "dr.low=[1]", "dr.high=[2]"], {},
     "unknown physics parameter 'mass:pol'"),
    ("train_box_reversed", "train", ["dr.params=[mass:pole]", "dr.low=[2]", "dr.high=[1]"], {},
     "low 2.0 must be below high 1.0"),
    ("train_box_lengths", "train", ["dr.params=[mass:pole]", "dr.low=[1,2]", "dr.high=[2]"], {}, "same length"),
    ("train_fixed_outside", "train", ["dr.fixed={mass:pole: -3}"], {}, "'mass:pole' = -3.0 is outside its physical bounds"),
    ("train_env_option", "train", ["env_options.episode_lenght=10"], {}, "unknown config key 'env_options.episode_lenght'. Did you mean: env_options.episode_length"),
    ("train_algo_option", "train", ["algo_options.alpha=1"], {}, "unknown config key 'algo_options.alpha'"),
    ("train_config_missing", "train", ["config=nope.yaml"], {}, "config file 'nope.yaml' not found"),
    ("train_config_yaml", "train", ["config=bad.yaml"], {"bad.yaml": "a: [1, 2\n"}, "config file 'bad.yaml' is not valid YAML"),
    ("train_config_list", "train", ["config=bad.yaml"], {"bad.yaml": "- 1\n- 2\n"}, "must hold a mapping"),
    ("train_name_path", "train", ["name=../escape"], {}, "name='../escape'"),
    ("train_resume_missing", "train", ["name=never", "resume=true"], {}, "no run named 'never'"),
    ("train_resume_overwrite", "train", ["resume=true", "overwrite=true", "name=x"], {}, "contradict"),
    ("train_overwrite_users_folder", "train", ["name=mine", "out_dir=.", "overwrite=true"], {},
     "name=./mine was not made by sim2real"),
    ("train_folder_exists", "train", ["name=mine", "out_dir=."], {}, "run folder './mine' exists"),
    # ---- evaluation -------------------------------------------------------------------------------------------
    ("eval_run_missing", "evaluate", ["run=nope", "x=mass:pole=1:2:3"], {}, "run=nope: not a run folder"),
    ("eval_needs_x", "evaluate", ["run=mine"], {}, "evaluate needs run=RUN_DIR and x="),
    ("eval_unknown_arg", "evaluate", ["run=mine", "x=mass:pole=1:2:3", "episode=2"], {}, "unknown config key 'episode'. Did you mean: episodes"),
    # ---- SimOpt -----------------------------------------------------------------------------------------------
    ("simopt_real_mode", "train", [f"config={os.path.join(ROOT, 'configs', 'simopt_pendulum.yaml')}",
                                   "algo_options.real=hardware"], {}, "algo_options.real='hardware' unknown"),
    ("simopt_no_recordings", "train", [f"config={os.path.join(ROOT, 'configs', 'simopt_pendulum.yaml')}",
                                       "algo_options.real=recordings", "algo_options.target={}"], {},
     "real=recordings needs algo_options.recordings="),
    ("simopt_no_target", "train", ["algo=simopt", "updates_per_chunk=1", "dr.params=[mass:pole]", "dr.low=[0.5]",
                                   "dr.high=[2]"], {}, "real=target needs algo_options.target="),
    ("simopt_chunk", "train", [f"config={os.path.join(ROOT, 'configs', 'simopt_pendulum.yaml')}",
                               "updates_per_chunk=10"], {}, "set updates_per_chunk=1"),
    ("simopt_bad_recording", "train", [f"config={os.path.join(ROOT, 'configs', 'simopt_pendulum.yaml')}",
                                       "algo_options.real=recordings", "algo_options.target={}",
                                       "algo_options.recordings=[bad.csv]"], {"bad.csv": "time,qpos:hinge\n0,nan\n"},
     "bad.csv"),
]


def _make(lab, files):
    for name, text in files.items():
        path = lab / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(text, str) and text.startswith("npz:"):
            np.savez(path, **{k: np.arange(60) * 0.01 for k in text[4:].split(",")})
        elif isinstance(text, bytes):
            path.write_bytes(text)
        else:
            path.write_text(text)


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_input(lab, capsys, case):
    _, script, argv, files, expect = case
    _make(lab, files)
    before = _snapshot(lab)
    with pytest.raises(SystemExit) as exc:
        main_guard(SCRIPTS[script].main, argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2, err
    assert expect in err, err
    assert "Traceback" not in err
    assert _snapshot(lab) == before  # nothing written, nothing removed or changed


def test_the_suite_is_large_enough():
    assert len(CASES) >= 60


# --------------------------------------------------------------------------------------------
# inputs that must work (they failed before)

def test_csv_with_a_byte_order_mark(lab):
    from sim2real.sysid.recordings import load
    import mujoco

    text = "\ufefftime,qpos:hinge,ctrl:motor\n" + GOOD.split("\n", 1)[1]
    (lab / "bom.csv").write_text(text, encoding="utf-8")
    rec = load("bom.csv", mujoco.MjModel.from_xml_path(PENDULUM))
    assert len(rec) == 60


def test_whole_numbers_in_float_notation_are_integers():
    from sim2real.common import config as config_lib
    from sim2real.training.driver import TrainConfig

    assert config_lib.load(TrainConfig, ["total_steps=1e5"]).total_steps == 100000
    with pytest.raises(config_lib.ConfigError, match="expected an integer"):
        config_lib.load(TrainConfig, ["total_steps=1.5"])


def test_sigterm_during_a_diagnosis_leaves_nothing_behind(tmp_path):
    """A scheduler's SIGTERM mid-diagnosis: exit status 130, no output folder, no hidden staging
    folder (the old tool left ``.diagnosis-XXXX`` behind)."""
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "diag"
    p = subprocess.Popen([sys.executable, os.path.join(ROOT, "scripts", "diagnose.py"), f"out={out}",
                          "progress=false"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while time.time() < deadline and not any(n.startswith(".diag.partial-") for n in os.listdir(tmp_path)):
        if p.poll() is not None:
            break
        time.sleep(0.05)
    assert p.poll() is None, "the diagnosis ended before it could be interrupted"
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert "interrupted" in err and "Traceback" not in err
    assert os.listdir(tmp_path) == []


_STUCK_TOOL = r"""
import sys, time
from sim2real.common import cli, output
cli.TERM_GRACE_S = 0.5

def job(argv):
    with output.staged(argv[0], kind="diagnosis") as tmp:
        open(tmp + "/half.txt", "w").write("half")
        end = time.time() + float(argv[1])
        told = False
        while True:  # a library that swallows the interrupt (or a hung C++ call)
            try:
                if not told:
                    told = print("staged", flush=True) or True
                if time.time() > end:
                    break
                time.sleep(0.05)
            except KeyboardInterrupt:
                pass

cli.main_guard(job, sys.argv[1:])
"""


@pytest.mark.parametrize("stuck_s", [30.0, 0.2], ids=["never-unwinds", "swallowed-then-finishes"])
def test_sigterm_that_is_swallowed_still_leaves_nothing_behind(tmp_path, stuck_s):
    """SIGTERM lands where it is swallowed: a tool stuck past the grace period is ended by the
    watchdog (staging folder removed, status 130); one that finishes its block afterwards does not
    move the result into place."""
    import signal
    import subprocess
    import sys

    out = tmp_path / "res"
    p = subprocess.Popen([sys.executable, "-c", _STUCK_TOOL, str(out), str(stuck_s)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, cwd=ROOT)
    assert p.stdout.readline().strip() == "staged"
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=20)
    assert p.returncode == 130, err
    assert "interrupted" in err and "Traceback" not in err
    assert os.listdir(tmp_path) == []
