"""Diagnose a sim-vs-real mismatch end to end: locate it, name the missing physics, fit, verify.

    out = diagnose(DiagnoseConfig(model="axis.xml", recordings=("a.csv",), heldout=("b.csv",), out="diag"))

Stages (each documented in its module): ``locate`` (where the nominal model is wrong),
``identify`` (fit and rank every candidate effect on inverse-dynamics residuals), ``simulate``
(short-horizon predictions on held-out recordings, before and after), ``export`` (fitted MJCF),
``report`` (plots, report.md, diagnosis.json). Everything is written to a temporary folder that
replaces ``out`` only when the whole diagnosis succeeded: a failure leaves nothing half-written.
"""
from __future__ import annotations

import dataclasses
import json
import os
import time

import numpy as np

from sim2real import output
from sim2real.progress import Bar
from sim2real.sysid import locate, report
from sim2real.sysid.candidates import EFFECTS, library
from sim2real.sysid.derivatives import smooth_derivatives, velocity_state, window_for
from sim2real.sysid.export import write_fitted_mjcf
from sim2real.sysid.identify import Identifier, rank, refine_by_simulation, ties
from sim2real.sysid.invdyn import InverseDynamics
from sim2real.sysid.recordings import check_sample_rate, load_all
from sim2real.sysid.simulate import Simulator
from sim2real.sysid.system import System


@dataclasses.dataclass(frozen=True)
class DiagnoseConfig:
    """Diagnosis settings (``scripts/diagnose.py key=value``).

    Attributes:
      model: nominal MJCF.
      recordings: recordings used for fitting.
      heldout: recordings used only to show the fit improve (default: the tail of each training one).
      out: output folder.
      overwrite: replace an existing output folder.
      effects: candidate effects searched (default: the whole library).
      window_seconds: Savitzky-Golay window for velocities/accelerations.
      val_fraction: tail of each training recording held out when ranking candidates.
      horizon_seconds: length of the short-horizon predictions (0: full open-loop replay).
      num_windows: time windows per recording when locating the mismatch.
      coulomb_eps: velocity scale of the smooth Coulomb model.
      min_gain: an effect must lower held-out error by this fraction to be named.
      verify_top: how many of the best-screened effects are verified by simulation.
      refine_evals: simulations spent refining each close contender (0: no refinement).
      tie_tolerance: effects whose verified error is within this fraction of the selected one's
        are reported as indistinguishable from it on these recordings (``indistinguishable``).
      plots: draw the figures of the report.
      progress: show progress while fitting candidates.
    """

    model: str = ""
    recordings: tuple[str, ...] = ()
    heldout: tuple[str, ...] = ()
    out: str = "runs/diagnosis"
    overwrite: bool = False
    effects: tuple[str, ...] = EFFECTS
    window_seconds: float = 0.02
    val_fraction: float = 0.3
    horizon_seconds: float = 1.0
    num_windows: int = 20
    coulomb_eps: float = 1e-3
    min_gain: float = 0.02
    verify_top: int = 4
    refine_evals: int = 80
    tie_tolerance: float = 0.01
    plots: bool = True
    progress: bool = True


def _signals(system: System, rec):
    """Measured signals of a recording: ``{'qpos:j': [T], 'force:a': [T]}``."""
    out = {f"qpos:{j}": rec.get("qpos", j) for j in system.joints}
    for a in system.actuators:
        f = rec.get("force", a)
        if f is not None:
            out[f"force:{a}"] = f
    return out


def predictions(system: System, sim: Simulator, z, rec, horizon: int, window: int,
                first: int = 0) -> dict[str, np.ndarray]:
    """Short-horizon predictions of every signal, aligned with the recording (NaN where none);
    segments start at sample ``first`` or later."""
    qpos, ctrl, _, qfrc = system.arrays(rec)
    if all(rec.get("qvel", j) is not None for j in system.joints):
        qvel = np.stack([rec.get("qvel", j) for j in system.joints], -1)
    else:
        _, qd_s, qdd_s = smooth_derivatives(qpos, rec.dt, window)
        qvel = velocity_state(qd_s, qdd_s, float(system.mj.opt.timestep), system.rk4)
    T = len(rec)
    starts, out = sim.predict(z, qpos, qvel, ctrl, qfrc, horizon, first=first)
    H = out["qpos"].shape[1]
    res = {name: np.full(T, np.nan) for name in _signals(system, rec)}
    for s, st in enumerate(starts):
        ok = out["ok"][s]
        for k, j in enumerate(system.joints):
            seg = np.where(ok, out["qpos"][s, :, system.mj.jnt_qposadr[k]], np.nan)
            res[f"qpos:{j}"][st + 1: st + 1 + H] = seg
        for a, an in enumerate(system.actuators):
            if f"force:{an}" in res:  # force of the step st+i -> st+i+1 is the force at sample st+i
                res[f"force:{an}"][st: st + H] = np.where(ok, out["force"][s, :, a], np.nan)
    return res


def score(system: System, sim: Simulator, z, recs, horizon: int, window: int, first=None):
    """Per-signal NRMSE (normalised by the measured signal's std) over recordings, and the predictions.

    ``first``: per recording, the sample where scoring starts (a held-back tail); the effect
    states before it come from the recording's start.
    """
    per, preds = {}, {}
    for k, rec in enumerate(recs):
        f0 = int(first[k]) if first is not None else 0
        p = predictions(system, sim, z, rec, horizon, window, f0)
        preds[rec.name] = p
        for name, meas in _signals(system, rec).items():
            ok = np.isfinite(p[name])
            per.setdefault(name, []).append((p[name][ok] - meas[ok], np.std(meas[f0:])))
    nr = {name: float(np.sqrt(np.mean(np.concatenate([e for e, _ in v]) ** 2)) / max(np.mean([s for _, s in v]), 1e-12))
          for name, v in per.items()}
    return nr, preds


def diagnose(cfg: DiagnoseConfig) -> dict:
    """Run the whole diagnosis; returns the content of ``diagnosis.json``."""
    if not cfg.model:
        raise ValueError("model=PATH.xml is required")
    if not cfg.recordings:
        raise ValueError("recordings=[a.csv,...] is required")
    inputs = [cfg.model, *cfg.recordings, *cfg.heldout]
    with output.staged(cfg.out, "diagnosis", inputs, cfg.overwrite) as tmp:
        return _run(cfg, tmp)


def _run(cfg: DiagnoseConfig, out: str) -> dict:
    t_start = time.time()
    system = System(cfg.model, coulomb_eps=cfg.coulomb_eps)
    train = load_all(list(cfg.recordings), system.mj, "training recordings")
    held = load_all(list(cfg.heldout), system.mj, "held-out recordings") if cfg.heldout else []
    for r in train + held:
        system.check_recording_covers(r)
    dt = train[0].dt
    check_sample_rate(held, dt, "the training recordings")
    window = window_for(dt, cfg.window_seconds)
    horizon = int(round(cfg.horizon_seconds / dt)) if cfg.horizon_seconds > 0 else max(len(r) for r in train + held)
    sim = Simulator(system, dt)
    idyn = InverseDynamics(system, train, window)
    ident = Identifier(idyn, cfg.val_fraction, window)
    z0 = ident.z0

    # ---- locate ---------------------------------------------------------------------------------
    nr0, preds0 = score(system, sim, z0, train, horizon, window)
    mismatch = {"signals": {}, "windows": {}, "worst_windows": [], "regimes": {}, "residual_offset_ratio": {}}
    errors = {}  # signal -> prediction errors over the training recordings (where predicted)
    for rec in train:
        meas = _signals(system, rec)
        for name, m in meas.items():
            err = preds0[rec.name][name] - m
            ws = locate.windows(rec.time, err, np.std(m), cfg.num_windows)
            mismatch["windows"].setdefault(name, {})[rec.name] = ws
            mismatch["worst_windows"] += [dict(w, recording=rec.name, signal=name) for w in ws]
            errors.setdefault(name, []).append(err[np.isfinite(err)])
    mismatch["worst_windows"].sort(key=lambda w: -w["nrmse"])
    mismatch["worst_windows"] = mismatch["worst_windows"][:10]
    for name, v in nr0.items():
        mismatch["signals"][name] = {"nrmse": v, "offset_ratio": locate.offset_ratio(np.concatenate(errors[name]))}
    r_nom = ident.r0
    dq, ddq, ctrl_rows = idyn.stacked("dq"), idyn.stacked("ddq"), idyn.stacked("ctrl")
    act_force = idyn.residual(z0, parts=("act",))  # modelled actuator force (generalised)
    m = system.mj
    for a, an in enumerate(system.actuators):
        j = int(m.actuator_trnid[a, 0])
        dof = m.jnt_dofadr[j]
        lim = float(m.actuator_forcerange[a, 1]) if m.actuator_forcelimited[a] and m.actuator_forcerange[a, 1] < 1e29 else None
        bounds = tuple(m.actuator_ctrlrange[a]) if m.actuator_ctrllimited[a] else None
        masks = locate.regimes(dq[:, dof], ddq[:, dof], act_force[:, dof], lim, ctrl_rows[:, a], bounds, window)
        mismatch["regimes"][system.joints[j]] = locate.regime_table(r_nom[:, dof], masks)
        mismatch["residual_offset_ratio"][system.joints[j]] = locate.offset_ratio(r_nom[:, dof])

    # ---- name the missing physics ----------------------------------------------------------------
    q_range = np.ptp(idyn.stacked("q"), axis=0)
    # in actuator-force units (before the gear), the units of the saturation limit (forcerange)
    force_scale = np.array([np.percentile(np.abs(act_force[:, m.jnt_dofadr[m.actuator_trnid[a, 0]]]), 99)
                            / max(abs(float(m.actuator_gear[a, 0])), 1e-12) for a in range(m.nu)])
    cands = library(system, dt, q_range, force_scale, tuple(cfg.effects))
    bar = Bar(cfg.progress, len(cands), "fitting candidates")
    fits = []
    for c in cands:
        fits.append(ident.fit(c))
        bar.step(text=f"fitted {c.label}")
    bar.close()
    # verify the front-runners by simulation on the held-back tail of the training recordings
    tail_start = [int(len(r) * (1 - cfg.val_fraction)) for r in train]

    def verify(fit):
        nr, _ = score(system, sim, fit.z, train, horizon, window, first=tail_start)
        return float(np.mean(list(nr.values())))

    def refine(fit, err):
        return refine_by_simulation(fit, system.spec, verify, err, cfg.refine_evals)

    ordered, selected, conf, weights, verified = rank(fits, cfg.min_gain, verify=verify, top_k=cfg.verify_top,
                                                      refine=refine if cfg.refine_evals > 0 else None)
    none = next(f for f in ordered if f.candidate.effect == "none")
    effect_rows = []
    for f, w in zip(ordered, weights):
        effect_rows.append({"effect": f.candidate.effect, "target": f.candidate.target,
                            "params": _effect_params(system, f), "std": {k: f.std.get(k) for k in _effect_params(system, f)},
                            "nominal_refit": {k: f.params[k] for k in system.nominal if k in f.params},
                            "score": f.bic - none.bic, "heldout_ratio": f.val_rmse / max(none.val_rmse, 1e-300),
                            "heldout_rmse": f.val_rmse, "weight": float(w),
                            "verified_nrmse": verified.get(f.candidate.label)})
    sel_row = next(r for r in effect_rows if r["effect"] == selected.candidate.effect
                   and r["target"] == selected.candidate.target)
    tied = ties(verified, selected.candidate.label, cfg.tie_tolerance)
    indistinguishable = [{"effect": f.candidate.effect, "target": f.candidate.target, "params": row["params"],
                          "verified_nrmse": row["verified_nrmse"]}
                         for f, row in zip(ordered, effect_rows) if f.candidate.label in tied]
    effect_rows.remove(sel_row)
    effect_rows.insert(0, sel_row)

    # ---- show the fit improve on held-out data -----------------------------------------------------
    check, check_first = (held, None) if held else (train, tail_start)
    z_fit = selected.z
    nr_b, pb = score(system, sim, z0, check, horizon, window, check_first)
    nr_a, pa = score(system, sim, z_fit, check, horizon, window, check_first)
    fit = {"metric": f"{cfg.horizon_seconds:g} s predictions from measured states" if cfg.horizon_seconds > 0
           else "open-loop replay",
           "recordings": [r.name for r in check], "before": float(np.mean(list(nr_b.values()))),
           "after": float(np.mean(list(nr_a.values()))),
           "per_signal": {k: {"before": nr_b[k], "after": nr_a[k]} for k in nr_b}}
    fitted_params = {k: float(v) for k, v in selected.params.items()}
    fit["reduction"] = 1 - fit["after"] / max(fit["before"], 1e-300)

    notes = []
    try:  # the last step: whatever happens here, the diagnosis itself is kept
        write_fitted_mjcf(cfg.model, system, z_fit, fitted_params, os.path.join(out, "fitted.xml"))
        fitted_mjcf = os.path.join(os.path.abspath(cfg.out), "fitted.xml")
    except Exception as e:  # noqa: BLE001
        fitted_mjcf = None
        notes.append(f"fitted.xml was not written: {type(e).__name__}: {e}")
    if indistinguishable:
        others = ", ".join(f"`{r['effect']}`" + (f" at {r['target']}" if r["target"] else "")
                           + " (" + ", ".join(f"{k} = {v:.4g}" for k, v in r["params"].items()) + ")"
                           for r in indistinguishable)
        notes.append(f"indistinguishable on these recordings: {others} predicts the held-back data as well "
                     f"as the selected effect (verified error within {100 * cfg.tie_tolerance:g}%); "
                     f"recordings with faster or richer commands would tell them apart")
    for name, v in fitted_params.items():
        if name.startswith("coulomb_asym:"):
            j = name.split(":", 1)[1]
            fc = fitted_params.get(f"coulomb:{j}", 0.0)
            notes.append(f"friction asymmetry on {j}: Fc+ = {fc * (1 + v):.4g}, Fc- = {fc * (1 - v):.4g}; "
                         f"the constant force offset during motion is Fc*asym = {fc * v:.4g}")
    d = {
        "model": os.path.abspath(cfg.model),
        "recordings": [r.path for r in train], "heldout": [r.path for r in held],
        "sample_period": dt, "smoothing_window_samples": window, "horizon_samples": horizon,
        "mismatch": mismatch, "effects": effect_rows, "selected": sel_row["effect"], "confidence": conf,
        "indistinguishable": indistinguishable,
        "fit": fit, "fitted_params": fitted_params, "fitted_mjcf": fitted_mjcf, "notes": notes,
        "seconds": round(time.time() - t_start, 1),
    }
    images = {}
    if cfg.plots:
        images = _plots(system, ident, selected, check, pb, pa, act_force, effect_rows, out)
    d["figures"] = list(images.values())
    report.markdown(os.path.join(out, "report.md"), d, images)
    with open(os.path.join(out, "diagnosis.json"), "w") as f:
        json.dump(d, f, indent=2, default=float)
    return d


def _effect_params(system: System, fit) -> dict[str, float]:
    """The parameters of the effect itself (not the nominal re-fit)."""
    return {k: v for k, v in fit.params.items() if k not in system.nominal}


def _plots(system, ident, selected, check, pb, pa, act, rows, out):
    """Figures of the report; ``act [N, nv]``: the nominal model's actuator force on the fit rows."""
    images = {}
    rec = check[0]
    meas = _signals(system, rec)
    worst = max(meas, key=lambda s: np.nanmean(np.abs(pb[rec.name][s] - meas[s])))
    err = np.abs(pb[rec.name][worst] - meas[worst])
    t_mid = rec.time[int(np.nanargmax(np.nan_to_num(err)))]
    span = 0.05 * (rec.time[-1] - rec.time[0])
    sig = {s: {"measured": meas[s], "nominal": pb[rec.name][s], "fitted": pa[rec.name][s]} for s in meas}
    report.overlay(os.path.join(out, "overlay.png"), rec.time, sig, f"held-out: {rec.name}",
                   zoom=(t_mid - span, t_mid + span))
    images["Sim vs real on held-out data"] = "overlay.png"
    r_fit = ident.idyn.residual(selected.z)
    tables = {"nominal": {}, "fitted": {}}
    m = system.mj
    dq, ddq, ctrl = ident.idyn.stacked("dq"), ident.idyn.stacked("ddq"), ident.idyn.stacked("ctrl")
    a0 = 0
    j = int(m.actuator_trnid[a0, 0])
    dof = m.jnt_dofadr[j]
    masks = locate.regimes(dq[:, dof], ddq[:, dof], act[:, dof], None, ctrl[:, a0], None, ident.window)
    tables["nominal"] = locate.regime_table(ident.r0[:, dof], masks)
    tables["fitted"] = locate.regime_table(r_fit[:, dof], masks)
    report.regimes_plot(os.path.join(out, "regimes.png"), tables, f"where the residual sits ({system.joints[j]})")
    images["Residual by regime"] = "regimes.png"
    report.residual_vs_velocity(os.path.join(out, "residual_vs_velocity.png"), dq[:, dof], ident.r0[:, dof],
                                r_fit[:, dof], system.joints[j])
    images["Residual vs velocity"] = "residual_vs_velocity.png"
    report.ranking_plot(os.path.join(out, "candidates.png"), rows)
    images["Candidate ranking"] = "candidates.png"
    return images
