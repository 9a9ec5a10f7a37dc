"""The sim-to-real loop: recordings from a policy, a diagnosis as a training distribution, one
iteration end to end on the pendulum."""
import json
import os

import jax
import numpy as np
import pytest
import yaml

from sim2real.common import config as config_lib
from sim2real.algos import from_diagnosis
from sim2real.algos.base import DRConfig
from sim2real.envs import make
from sim2real.tools.loop import env_model_path
from sim2real.tools.record import native, simulated
from sim2real.sysid import recordings as rec_lib
from sim2real.training.driver import TrainConfig, train

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PLANT = os.path.join(ROOT, "benchmarks", "plants", "pendulum_real.xml")
SHORT = ["env_options.episode_length=40"]  # 2 s episodes: 200 samples at the plant's 100 Hz


def tiny(tmp_path, *extra):
    return config_lib.load(TrainConfig, [
        f"out_dir={tmp_path}", "env=pendulum", "total_steps=1024", "updates_per_chunk=2", "progress=false",
        "tensorboard=false", "ppo.num_envs=8", "ppo.num_steps=16", "ppo.num_minibatches=2", "ppo.num_epochs=2",
        "ppo.net.hidden=[16,16]", *SHORT, *extra])


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("loop")
    return train(tiny(tmp, "name=nominal"))["run_dir"]


def _script(name):
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"script_{name}", os.path.join(ROOT, "scripts", f"{name}.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _constant_policy(env, u: float = 0.0):
    """Every env gets the command ``u`` (ctrl units) at every step."""
    def act(obs, carry, first, key):
        return np.full((obs.shape[0], env.action_size), u, np.float32), carry

    act.carry_size = 0
    return act


def test_native_plant_matches_the_env_on_the_envs_own_model():
    """The env's MJCF stepped by native MuJoCo and the MJX env, from the same state under the same
    (zero) commands, agree; the native log has a row per physics step."""
    env = make("pendulum", episode_length=10)
    act = _constant_policy(env)
    a = native(env, env_model_path(env), act, 2, jax.random.PRNGKey(0))
    assert a.dt == pytest.approx(0.01) and a.qpos.shape == (2, 51, 1) and np.all(a.length == 51)
    sub = a.every(5)
    assert sub.dt == pytest.approx(env.dt) and sub.qpos.shape == (2, 11, 1)
    z = jax.numpy.asarray(env.default_z())
    step = jax.jit(env.step)  # (an eager MJX step costs seconds)
    for e in range(2):
        s = env.reset(jax.random.PRNGKey(0), z)
        s = s.replace(data=s.data.replace(qpos=jax.numpy.asarray(a.qpos[e, 0], jax.numpy.float32),
                                          qvel=jax.numpy.asarray(a.qvel[e, 0], jax.numpy.float32)))
        qs = [s.data.qpos[0]]
        for _ in range(10):
            s = step(s, jax.numpy.zeros(1), z)
            qs.append(s.data.qpos[0])
        assert np.ptp(sub.qpos[e, :, 0]) > 1e-3  # it moved
        np.testing.assert_allclose(np.array(qs), sub.qpos[e, :, 0], atol=2e-4)
    b = simulated(env, env.default_z(), act, 2, jax.random.PRNGKey(0))
    assert b.dt == pytest.approx(env.dt) and b.qpos.shape == (2, 11, 1)


def test_a_fall_ends_the_log_unless_recorded_until_the_end():
    """A hopper under full torque falls (the env terminates it); ``until_end`` logs on to the
    episode's length, the same samples up to the fall, the same return (counted to the fall)."""
    env = make("hopper", episode_length=60)
    act = _constant_policy(env, 1.0)
    a = native(env, env_model_path(env), act, 2, jax.random.PRNGKey(0))
    b = native(env, env_model_path(env), act, 2, jax.random.PRNGKey(0), until_end=True)
    full = 60 * 4 + 1  # 4 physics steps of 2 ms per control step, and the initial state
    assert np.all(a.length < full) and np.all(b.length == full)
    np.testing.assert_array_equal(a.ret, b.ret)
    for e in range(2):
        n = int(a.length[e])
        np.testing.assert_array_equal(a.qpos[e, :n], b.qpos[e, :n])
        assert np.ptp(b.qpos[e, n:, 2]) > 0.05  # it went on moving after the fall (torso angle, rad)


@pytest.mark.slow  # compiles the hopper's MJX rollout twice (80 s on 2 cores)
def test_a_fall_in_the_env_is_logged_until_the_end_when_asked():
    env = make("hopper", episode_length=60)
    act = _constant_policy(env, 1.0)
    a = simulated(env, env.default_z(), act, 2, jax.random.PRNGKey(0))
    b = simulated(env, env.default_z(), act, 2, jax.random.PRNGKey(0), until_end=True)
    assert np.all(a.length < 61) and np.all(b.length == 61)
    np.testing.assert_allclose(a.ret, b.ret, rtol=1e-5)  # two compiled programs: float32 rounding
    n = int(a.length[0])
    np.testing.assert_allclose(a.qpos[0, :n], b.qpos[0, :n], atol=1e-5)


def test_recordings_round_trip_into_the_diagnosis_reader(tmp_path):
    env = make("pendulum", episode_length=10)
    r = native(env, PLANT, _constant_policy(env), 2, jax.random.PRNGKey(1), noise=1e-3)
    paths = r.write(str(tmp_path))
    rec = rec_lib.load(paths[0], env.mj_model)
    assert rec.dt == pytest.approx(0.01) and len(rec) == 51
    assert set(rec.columns) == {"qpos:hinge", "qvel:hinge", "ctrl:motor"}


def test_native_target_must_have_the_envs_joints(tmp_path):
    env = make("pendulum", episode_length=5)
    xml = tmp_path / "other.xml"
    xml.write_text(open(PLANT).read().replace('name="hinge"', 'name="axle"').replace('joint="hinge"', 'joint="axle"'))
    with pytest.raises(KeyError, match="unknown joint.*hinge"):
        native(env, str(xml), _constant_policy(env), 1, jax.random.PRNGKey(0))


def _diagnosis(tmp_path, model, fitted, selected, nominal=None, period=0.01):
    d = {"model": model, "sample_period": period, "fitted_params": fitted, "selected": selected,
         "nominal_refit": nominal or {}}
    os.makedirs(tmp_path, exist_ok=True)
    with open(os.path.join(tmp_path, "diagnosis.json"), "w") as f:
        json.dump(d, f)
    return str(tmp_path)


def test_diagnosis_becomes_the_physics_and_a_box_around_it(tmp_path):
    env = make("pendulum")
    diag = _diagnosis(tmp_path, env_model_path(env),
                      {"mass:pole": 1.1, "coulomb:hinge": 0.3, "action_delay": 6.0},
                      [{"effect": "coulomb_friction", "target": "hinge", "std": {"coulomb:hinge": 0.01}},
                       {"effect": "action_delay", "target": "", "std": {"action_delay": float("nan")}}],
                      {"mass:pole": {"nominal": 1.0, "fitted": 1.1, "std": 0.05}})
    dr = from_diagnosis.resolve(DRConfig(params=("mass:pole",), low=(0.9,), high=(1.2,), from_diagnosis=diag,
                                         diagnosis_k=2.0), env)
    box = dict(zip(dr.params, zip(dr.low, dr.high)))
    assert box["mass:pole"] == (0.9, 1.2)  # the user's own box wins
    assert box["coulomb:hinge"] == pytest.approx((0.28, 0.32))
    # 6 samples of 10 ms = 60 ms = 1.2 control steps of 50 ms; no std: held at the fitted value
    assert dr.fixed == {"action_delay": pytest.approx(1.2)}
    # resolving the resolved config again changes nothing (what a resume would see)
    assert from_diagnosis.resolve(dr, env) == dr
    # ``span``: each box reaches back to the env's own value (no friction, no delay), the
    # delay without a std too; a value at the env's own stays fixed
    span = from_diagnosis.resolve(DRConfig(from_diagnosis=diag, diagnosis_k=2.0, diagnosis_box="span"), env)
    box = dict(zip(span.params, zip(span.low, span.high)))
    assert box["coulomb:hinge"] == pytest.approx((0.0, 0.32))
    assert box["action_delay"] == pytest.approx((0.0, 1.2)) and "action_delay" not in span.fixed
    assert box["mass:pole"] == pytest.approx((env.spec["mass:pole"].default, 1.2))
    assert from_diagnosis.resolve(span, env) == span
    # ``centred``: as far past the fitted value as back to the env's own, clipped to the bounds
    # (the friction's and the delay's 0); past k std where the fit moved less than that
    mid = from_diagnosis.resolve(DRConfig(from_diagnosis=diag, diagnosis_k=2.0, diagnosis_box="centred"), env)
    box = dict(zip(mid.params, zip(mid.low, mid.high)))
    assert box["coulomb:hinge"] == pytest.approx((0.0, 0.6))
    assert box["action_delay"] == pytest.approx((0.0, 2.4))
    m0 = env.spec["mass:pole"].default
    assert box["mass:pole"] == pytest.approx((m0, 2.2 - m0))
    assert from_diagnosis.box(1.0, 0.2, 0.9, 2.0, "centred") == pytest.approx((0.6, 1.4))
    assert from_diagnosis.resolve(mid, env) == mid
    with pytest.raises(config_lib.ConfigError, match="dr.diagnosis_box='wide'"):
        from_diagnosis.resolve(DRConfig(from_diagnosis=diag, diagnosis_box="wide"), env)


def test_a_mass_the_diagnosis_flags_as_standing_in_for_missing_physics_is_not_trained_on(tmp_path):
    env = make("pendulum")
    diag = _diagnosis(tmp_path, env_model_path(env), {"mass:pole": 13.0, "coulomb:hinge": 0.3},
                      [{"effect": "coulomb_friction", "target": "hinge", "std": {"coulomb:hinge": 0.01}}],
                      {"mass:pole": {"nominal": 1.0, "fitted": 13.0, "std": 0.5}})
    with pytest.warns(UserWarning, match="mass:pole was re-fitted 13, more than 10x off"):
        dr = from_diagnosis.resolve(DRConfig(from_diagnosis=diag, diagnosis_k=2.0), env)
    assert "mass:pole" not in dr.params and "mass:pole" not in dr.fixed  # the env keeps its own
    assert "coulomb:hinge" in dr.params


def test_refitted_damping_on_a_joint_the_env_randomises_through_its_viscous_effect(tmp_path):
    """The cart-pole env's joint_damping is the hinge's; a re-fitted rail damping becomes the rail's
    viscous effect (the excess over the nominal 5e-4 N s/m); a fit below the nominal keeps it."""
    env = make("cartpole")
    refit = lambda v: {"damping:slider": {"nominal": 5e-4, "fitted": v, "std": 1e-4}}
    more = _diagnosis(tmp_path / "a", env_model_path(env), {"damping:slider": 0.0105}, [], refit(0.0105))
    dr = from_diagnosis.resolve(DRConfig(from_diagnosis=more, diagnosis_k=2.0), env)
    assert dict(zip(dr.params, zip(dr.low, dr.high)))["viscous:slider"] == pytest.approx((0.0098, 0.0102))
    less = _diagnosis(tmp_path / "b", env_model_path(env), {"damping:slider": 1e-4}, [], refit(1e-4))
    with pytest.warns(UserWarning, match="can only add damping"):
        dr = from_diagnosis.resolve(DRConfig(from_diagnosis=less, diagnosis_k=2.0), env)
    assert dict(zip(dr.params, zip(dr.low, dr.high)))["viscous:slider"] == pytest.approx((0.0, 2e-4))


def test_diagnosis_of_another_model_or_an_unknown_parameter_is_refused(tmp_path):
    env = make("pendulum")
    other = _diagnosis(tmp_path / "a", os.path.join(ROOT, "sim2real", "envs", "assets", "cartpole.xml"),
                       {"coulomb:hinge": 0.3}, [])
    with pytest.raises(config_lib.ConfigError, match="not env 'pendulum''s"):
        from_diagnosis.resolve(DRConfig(from_diagnosis=other), env)
    payload = _diagnosis(tmp_path / "b", env_model_path(env), {"payload:pole": 0.2, "payload_r:pole": 0.7},
                         [{"effect": "mass_offset", "target": "pole", "std": {"payload:pole": 0.01, "payload_r:pole": 0.1}}])
    with pytest.raises(config_lib.ConfigError, match="payload_r:pole have no counterpart"):
        from_diagnosis.resolve(DRConfig(from_diagnosis=payload), env)
    with pytest.raises(config_lib.ConfigError, match="no diagnosis.json"):
        from_diagnosis.resolve(DRConfig(from_diagnosis=str(tmp_path / "missing")), env)


def test_record_script_writes_what_the_diagnosis_reads(run_dir, tmp_path):
    record = _script("record")

    out = tmp_path / "rec"
    record.main([f"run={run_dir}", f"target={PLANT}", "episodes=2", f"out={out}", "noise=1e-3", "progress=false"])
    files = sorted(f for f in os.listdir(out) if not f.startswith("."))
    assert files[:2] == ["episode_000.csv", "episode_001.csv"] and "record.json" in files
    env = make("pendulum")
    rec = rec_lib.load(str(out / "episode_001.csv"), env.mj_model)
    assert rec.dt == pytest.approx(0.01) and len(rec) == 201
    what = json.load(open(out / "record.json"))
    assert len(what["returns"]) == 2 and what["simulator"].startswith("native MuJoCo")
    # the env itself as target, with physics values: logged per control step
    record.main([f"run={run_dir}", "target=coulomb:hinge=0.3", "episodes=2", f"out={tmp_path / 'sim'}",
                 "progress=false"])
    assert rec_lib.load(str(tmp_path / "sim" / "episode_000.csv"), env.mj_model).dt == pytest.approx(0.05)
    with pytest.raises(KeyError, match="unknown parameter|nope"):
        record.main([f"run={run_dir}", "target=nope=1", "episodes=1", f"out={tmp_path / 'x'}", "progress=false"])
    assert not os.path.exists(tmp_path / "x")


def test_one_loop_iteration_end_to_end(tmp_path):
    """Train, record on the 'real' pendulum, diagnose, retrain from the diagnosis: one call, as
    from the shell, in a process whose JAX has 64-bit types on (``JAX_ENABLE_X64=1``: training
    and the diagnosis stopped on a float64 scan carry before ``_precision.py``)."""
    from sim2real.common.cli import main_guard

    loop = _script("loop")

    out = tmp_path / "loop"
    argv = ["env=pendulum", "total_steps=1024", "updates_per_chunk=2", "tensorboard=false", "ppo.num_envs=8",
            "ppo.num_steps=16", "ppo.num_minibatches=2", "ppo.num_epochs=2", "ppo.net.hidden=[16,16]", *SHORT,
            f"target={PLANT}", "episodes=2", "eval_episodes=2", f"out={out}", "progress=false", "noise=1e-3",
            "diagnose.effects=[coulomb_friction,action_delay]",  # (a toy policy: keep the answer to what the env can take)
            "warm_start=true", "warm_std=0.6"]
    with jax.enable_x64(True):
        main_guard(loop.main, argv)
        assert jax.config.jax_enable_x64  # (restored after the command)
    res = json.load(open(out / "loop.json"))
    assert set(res["scores"]) == {"nominal", "iter_1"}
    cfg = yaml.safe_load(open(out / "iter_1" / "run" / "config.yaml"))
    assert cfg["dr"]["from_diagnosis"].endswith("diagnosis")
    assert cfg["algo_options"]["warm_start"] == str(out / "nominal")  # fine-tunes the recorded policy
    assert cfg["algo_options"]["warm_std"] == 0.6                        # ... with its exploration restarted
    assert "warm_std" not in yaml.safe_load(open(out / "nominal" / "config.yaml"))["algo_options"]
    d = json.load(open(out / "iter_1" / "diagnosis" / "diagnosis.json"))
    # whatever was fitted is the new run's physics: in its box or fixed
    for name in d["fitted_params"]:
        name = "joint_damping" if name.startswith("damping:") else name
        assert name in cfg["dr"]["params"] or name in cfg["dr"]["fixed"], name
    assert os.path.exists(out / "iter_1" / "run" / "policy.msgpack")


def test_a_diagnosis_the_loop_cannot_use_trains_on_the_fallback_box(run_dir, tmp_path, monkeypatch):
    """An inconclusive diagnosis, or one whose masses stand in for something else (> 10x off),
    is not trained on when a fallback box is given; without one it is, with a warning. A bad
    fallback is refused before anything is trained."""
    import importlib

    from sim2real.tools import loop

    diag_lib = importlib.import_module("sim2real.sysid.diagnose")  # (the package exports the function by that name)

    ok = {"answer": "effects", "nominal_refit": {"mass:pole": {"nominal": 1.0, "fitted": 1.2, "unit": "kg"}}}
    far = {"answer": "effects", "nominal_refit": {"mass:pole": {"nominal": 1.0, "fitted": 14.0, "unit": "kg"}}}
    assert loop.unusable(ok) is None
    assert "mass:pole 1 -> 14 kg" in loop.unusable(far)
    assert loop.unusable(dict(ok, answer="inconclusive")) == "the diagnosis is inconclusive"

    def fake(cfg):  # what the hopper's 0.1 s recordings gave: an effect beside far masses
        os.makedirs(cfg.out, exist_ok=True)
        return dict(far, selected=[], fitted_params={"mass:pole": 14.0}, fit={"before": 1.0, "after": 0.5})

    monkeypatch.setattr(diag_lib, "diagnose", fake)
    box = DRConfig(params=("coulomb:hinge",), low=(0.0,), high=(0.6,))
    it = loop.iteration(run_dir, tiny(tmp_path), PLANT, str(tmp_path / "it"), 2, noise=1e-3, fallback=box)
    assert it["trained_on"] == "fallback" and "x14" in it["why"]
    cfg = yaml.safe_load(open(os.path.join(it["run"], "config.yaml")))
    assert cfg["dr"]["params"] == ["coulomb:hinge"] and cfg["dr"]["high"] == [0.6] and not cfg["dr"]["from_diagnosis"]
    with pytest.raises(config_lib.ConfigError, match="fallback box for .coulomb:hinge.: low 0.5 must be below high 0.1"):
        _script("loop").main(["env=pendulum", f"target={PLANT}", f"out={tmp_path / 'bad'}", "fallback.params=[coulomb:hinge]",
                              "fallback.low=[0.5]", "fallback.high=[0.1]"])
    assert not os.path.exists(tmp_path / "bad")


def test_a_diagnosed_delay_past_the_envs_delay_line_lengthens_it(run_dir, tmp_path, monkeypatch):
    """A fitted delay whose box (value +- k std) reaches past the env's delay line (4 control
    steps) is trained with a line long enough for it, not refused (the hopper's 4.34 steps)."""
    import importlib

    from sim2real.tools import loop

    diag_lib = importlib.import_module("sim2real.sysid.diagnose")
    env = make("pendulum")
    steps, sd = 5.2, 0.3  # in recording samples at twice the control rate: 10.4 and 0.6 samples

    def fake(cfg):
        d = {"model": env_model_path(type(env)), "answer": "effects", "sample_period": env.dt / 2,
             "fitted_params": {"action_delay": 2 * steps}, "nominal_refit": {},
             "selected": [{"effect": "action_delay", "target": "", "params": {"action_delay": 2 * steps},
                           "std": {"action_delay": 2 * sd}}], "fit": {"before": 1.0, "after": 0.5}}
        os.makedirs(cfg.out)
        with open(os.path.join(cfg.out, "diagnosis.json"), "w") as f:
            json.dump(d, f)
        return d

    monkeypatch.setattr(diag_lib, "diagnose", fake)
    it = loop.iteration(run_dir, tiny(tmp_path), PLANT, str(tmp_path / "it"), 2, noise=1e-3)
    assert from_diagnosis.delay_line(os.path.join(tmp_path, "it", "diagnosis"), env, 2.0) == 6  # ceil(5.2 + 2 * 0.3)
    assert from_diagnosis.delay_line(os.path.join(tmp_path, "it", "diagnosis"), env, 2.0, "centred") == 11  # 2 * 5.2
    cfg = yaml.safe_load(open(os.path.join(it["run"], "config.yaml")))
    assert cfg["env_options"]["max_delay"] == 6
    i = cfg["dr"]["params"].index("action_delay")
    assert cfg["dr"]["low"][i] == pytest.approx(steps - 2 * sd) and cfg["dr"]["high"][i] == pytest.approx(steps + 2 * sd)


@pytest.fixture(scope="module")
def dr_run(tmp_path_factory):
    """A tiny 2-seed run with a 2-D DR box (shared: each training costs a compilation)."""
    return train(tiny(tmp_path_factory.mktemp("dr"), "name=dr", "num_seeds=2", "dr.params=[mass:pole,coulomb:hinge]",
                      "dr.low=[0.5,0.0]", "dr.high=[1.5,0.2]"))["run_dir"]


def test_evaluation_holds_the_box_centre_names_its_folder_by_axes_and_keeps_every_seed(dr_run):
    from sim2real.tools.evaluate import EvaluateConfig, evaluate_run

    run = dr_run
    res = evaluate_run(EvaluateConfig(run=run, x="mass:pole=0.5,1.5", episodes=1, progress=False))
    env = make("pendulum")
    assert res["held"] == {"coulomb:hinge": pytest.approx(0.1)}          # not the env default, 0
    np.testing.assert_allclose(res["z"][:, env.spec.index("coulomb:hinge")], 0.1, rtol=1e-6)
    assert res["out"] == os.path.join(run, "eval", "mass-pole")
    header = open(os.path.join(res["out"], "returns.csv")).readline().strip()
    assert header == "mass:pole,return,std,seed_0,seed_1"
    assert os.path.getsize(os.path.join(res["out"], "returns.png")) > 0
    assert res["std"].shape == (2,) and np.all(res["std"] >= 0)


def test_evaluation_writes_a_video_per_grid_corner(dr_run, tmp_path):
    from PIL import Image

    from sim2real.common.video import gl_backend
    from sim2real.tools.evaluate import EvaluateConfig, evaluate_run

    try:
        gl_backend()
    except RuntimeError as e:  # no EGL nor OSMesa on this machine: nothing to render with
        pytest.skip(str(e))
    res = evaluate_run(EvaluateConfig(run=dr_run, x="mass:pole=0.5:1.5:3", y="coulomb:hinge=0.0,0.2", episodes=1,
                                      out=str(tmp_path / "ev"), videos=True, progress=False))
    gifs = sorted(f for f in os.listdir(res["out"]) if f.endswith(".gif"))
    assert gifs == sorted(["video_mass-pole=0.5__coulomb-hinge=0.gif", "video_mass-pole=0.5__coulomb-hinge=0.2.gif",
                           "video_mass-pole=1.5__coulomb-hinge=0.gif", "video_mass-pole=1.5__coulomb-hinge=0.2.gif"])
    frames = [np.asarray(Image.open(os.path.join(res["out"], g)).convert("RGB")) for g in gifs]
    assert frames[0].shape == (240, 320, 3) and not np.array_equal(frames[0], frames[3])  # labels differ


def test_loggers_tensorboard_text_and_hparams_and_wandb_offline(tmp_path, monkeypatch):
    """TensorBoard gets the resolved config as text and the settings as hparams; logger=wandb goes
    through a stand-in ``wandb`` module (the package is not a dependency): what sim2real hands it;
    and a clear error, before any folder exists, when it is missing."""
    import glob
    import sys
    import types

    calls = {"init": [], "log": [], "finish": 0}

    class FakeRun:
        def log(self, data, step):
            calls["log"].append((step, data))

        def finish(self):
            calls["finish"] += 1

    fake = types.ModuleType("wandb")
    fake.init = lambda **kw: calls["init"].append(kw) or FakeRun()
    monkeypatch.setitem(sys.modules, "wandb", fake)
    train(tiny(tmp_path, "name=wb", "logger=wandb", "tensorboard=true", "ppo.lr=0.00123"))
    blobs = b"".join(open(p, "rb").read() for p in glob.glob(str(tmp_path / "wb" / "tb" / "**" / "events.*"),
                                                             recursive=True))
    assert b"lr: 0.00123" in blobs                        # the resolved config, as text
    assert b"hparam/episode_return" in blobs and b"ppo.lr" in blobs and b"ppo.net.hidden" in blobs
    (kw,) = calls["init"]
    assert kw["mode"] == "offline" and kw["project"] == "sim2real" and kw["config"]["ppo"]["num_envs"] == 8
    assert kw["dir"] == str(tmp_path / "wb")
    steps = [s for s, _ in calls["log"]]
    assert steps == sorted(steps) and len(steps) >= 2 and "episode_return" in calls["log"][-1][1]
    assert calls["finish"] == 1

    monkeypatch.setitem(sys.modules, "wandb", None)  # not installed
    with pytest.raises(config_lib.ConfigError, match="logger=wandb needs the wandb package"):
        train(tiny(tmp_path, "name=wb2", "logger=wandb"))
    assert not (tmp_path / "wb2").exists()


def test_render_draws_the_nominal_and_the_box_corners_side_by_side(tmp_path, dr_run):
    from PIL import Image

    from sim2real.common.video import gl_backend
    from sim2real.tools import render

    try:
        gl_backend()
    except RuntimeError as e:  # no EGL nor OSMesa on this machine: nothing to render with
        pytest.skip(str(e))
    run = dr_run
    out = tmp_path / "v.gif"
    _script("render").main([f"run={run}", f"out={out}", "steps=12", "width=64", "height=48"])
    gif = Image.open(out)
    assert gif.size == (3 * 64, 48) and gif.n_frames == 13       # three panels, the first state + 12 steps
    frame = np.asarray(gif.convert("RGB"))
    assert not np.array_equal(frame[:, :64], frame[:, 64:128])    # the panels differ (labels, physics)
    with pytest.raises(FileExistsError, match="overwrite=true"):
        _script("render").main([f"run={run}", f"out={out}"])
    with pytest.raises(config_lib.ConfigError, match="a .gif or .mp4"):
        _script("render").main([f"run={run}", f"out={tmp_path / 'v.avi'}"])


def test_loop_settings_that_cannot_apply_are_refused():
    from sim2real.common.config import ConfigError
    from sim2real.tools.loop import LoopConfig

    with pytest.raises(ConfigError, match="warm_std=0.6: restarts a warm start's exploration; set warm_start=true"):
        LoopConfig(target="real.xml", out="o", warm_std=0.6)
    with pytest.raises(ConfigError, match="warm_std=-1"):
        LoopConfig(target="real.xml", out="o", warm_start=True, warm_std=-1.0)
    with pytest.raises(ConfigError, match="episodes=1"):
        LoopConfig(target="real.xml", out="o", episodes=1)
    assert LoopConfig(target="real.xml", out="o", warm_start=True, warm_std=0.6).warm_std == 0.6


def test_closed_loop_plants_hold_the_truth_the_benchmark_trains_its_oracle_on(monkeypatch):
    """``benchmarks/closed_loop.py`` writes each plant's effects twice: in the plant's MJCF (what
    is scored) and as the env's physics (``truth``: what the oracle trains on). The hopper plants'
    payload and lags must agree, and every truth must be a valid physics vector inside its wide
    box (the held-out plant's values were chosen off the box's centre, not outside it)."""
    import importlib

    import mujoco

    monkeypatch.syspath_prepend(os.path.join(ROOT, "benchmarks"))
    closed_loop = importlib.import_module("closed_loop")

    for name, setup in closed_loop.SETUPS.items():
        env = make(config_lib.load(TrainConfig, [f"config={os.path.join(ROOT, setup['config'])}"]).env)
        env.z_of(**setup["truth"])  # bounds and names checked
        for p, v in setup["truth"].items():
            if p in setup["wide"]:
                lo, hi = setup["wide"][p]
                assert lo <= v <= hi, (name, p, v)
        if not name.startswith("hopper"):
            continue
        m = mujoco.MjModel.from_xml_path(os.path.join(ROOT, setup["plant"]))
        payload = m.body_mass[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "payload")]
        assert payload == pytest.approx(setup["truth"]["payload:torso"]), name
        for motor in ("thigh", "leg", "foot"):
            a = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, motor)
            assert m.actuator_dynprm[a, 0] == pytest.approx(setup["truth"][f"motor_lag:{motor}"]), (name, motor)
