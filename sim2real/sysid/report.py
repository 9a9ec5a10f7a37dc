"""Figures and the Markdown report of a diagnosis (units from the parameter spec)."""
from __future__ import annotations

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from sim2real.physics.kinds.base import actuator_is_linear  # noqa: E402


def _stitch(sh, pred, tiles, key, k, traj_index):
    """Predictions of segments of one trajectory placed on its time axis (NaN elsewhere)."""
    tr = sh.trajs[traj_index]
    out = np.full(len(tr), np.nan)
    for i, s in enumerate(tiles):
        if sh.tiles.traj[s] != traj_index:
            continue
        st = int(sh.tiles.local[s])
        seg = np.where(pred["ok"][0][i], pred[key][0][i, :, k], np.nan)
        out[st + 1: st + 1 + sh.H] = seg
    return out


def overlay(path, sh, tiles, pred_b, pred_a, traj_index, names, units):
    """Measured vs nominal vs fitted predictions, one panel per signal, residuals underneath."""
    tr = sh.trajs[traj_index]
    rows = []
    for key in sh.signals:
        for k, nm in enumerate(names[key]):
            rows.append((key, k, nm))
    fig, axes = plt.subplots(2 * len(rows), 1, figsize=(9, 2.3 * len(rows) + 0.8), squeeze=False,
                             gridspec_kw={"height_ratios": [3, 1.3] * len(rows)}, sharex=True)
    for r, (key, k, nm) in enumerate(rows):
        meas = {"qpos": tr.q, "qvel": tr.qvel, "force": tr.force}[key][:, sh.qvel_cols[k] if key == "qvel" else k]
        nb, na = _stitch(sh, pred_b, tiles, key, k, traj_index), _stitch(sh, pred_a, tiles, key, k, traj_index)
        ax, ax2 = axes[2 * r, 0], axes[2 * r + 1, 0]
        ax.plot(tr.time, meas, "k", lw=1.1, label="measured")
        ax.plot(tr.time, nb, "C3", lw=0.9, alpha=0.85, label="nominal model")
        ax.plot(tr.time, na, "C0", lw=0.9, alpha=0.85, label="fitted model")
        for s in tiles:
            if sh.tiles.traj[s] == traj_index:
                ax.axvline(tr.time[int(sh.tiles.local[s])], color="0.85", lw=0.5, zorder=0)
        ax.set_ylabel(f"{nm} [{units.get(nm, '')}]", fontsize=8)
        ax2.plot(tr.time, nb - meas, "C3", lw=0.8)
        ax2.plot(tr.time, na - meas, "C0", lw=0.8)
        ax2.axhline(0, color="k", lw=0.5)
        ax2.set_ylabel("error", fontsize=7)
        for a in (ax, ax2):
            a.tick_params(labelsize=7)
        if r == 0:
            ax.legend(fontsize=7, ncol=3)
            ax.set_title(f"{tr.name}: {sh.H * tr.dt:.3g} s predictions from measured states (grey lines: segment starts)",
                         fontsize=9)
    axes[-1, 0].set_xlabel("time [s]", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def steps_plot(path, steps: list[dict]):
    """Validation and held-out error after each forward-selection step (lower is better)."""
    fig, ax = plt.subplots(figsize=(6.5, 0.45 * len(steps) + 1.6))
    labels = [s["model"] for s in steps]
    y = np.arange(len(steps))
    v0, h0 = steps[0]["validation"], steps[0]["heldout_nrmse"]
    ax.barh(y - 0.18, [s["validation"] / v0 for s in steps], 0.36, color="C0", label="validation segments")
    ax.barh(y + 0.18, [s["heldout_nrmse"] / h0 for s in steps], 0.36, color="C2", label="held-out NRMSE")
    for yi, s in zip(y, steps):
        if not s["kept"]:
            ax.text(0.02, yi, "not kept (held-out check)", fontsize=7, va="center", color="C3")
    ax.set_yticks(y, labels, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("prediction error relative to the nominal re-fit ('none'); lower is better")
    ax.legend(fontsize=7)
    ax.set_title("forward selection: error after each step", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def segments_plot(path, steps: list[dict], before: list[float]):
    """Each step's prediction error on every held-out segment (``heldout_segments``; the model
    file's, ``before``, in grey). The held-out check pools the segments, so a gain carried by
    most of them can be undone by one that every model mispredicts, and a pooled gain can come
    from a few segments alone: this shows which."""
    fig, ax = plt.subplots(figsize=(6.5, 3.4))
    x = np.arange(1, len(before) + 1)
    ax.plot(x, before, "o-", ms=3, lw=0.8, color="C7", label="model file")
    for k, s in enumerate(steps):
        ax.plot(x, s["heldout_segments"], "o-" if s["kept"] else "x--", ms=3, lw=0.8, color=f"C{k % 10}",
                label=("nominal re-fit (none)" if k == 0 else s["model"]) + ("" if s["kept"] else " (not kept)"))
    ax.set_yscale("log")
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.set_xlabel("held-out segment (in recording order)")
    ax.set_ylabel("prediction error (NRMSE)")
    ax.set_title("held-out error per segment after each step (lower is better)", fontsize=9)
    ax.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def ranking_plot(path, rows: list[dict], top: int = 14):
    """The first round's screen, best score first (a fitted candidate shows its validation ratio)."""
    rows = rows[:top]
    fig, ax = plt.subplots(figsize=(6.5, 0.33 * len(rows) + 1.4))
    labels = [f"{r['effect']}@{r['target']}" if r["target"] else r["effect"] for r in rows]
    vals = [max(r["screen_score"], 0.0) for r in rows]
    colors = ["C0" if r.get("passed") else ("C1" if "validation_ratio" in r else "C7") for r in rows]
    ax.barh(range(len(rows)), vals, color=colors)
    for i, r in enumerate(rows):
        if "validation_ratio" in r:
            ax.text(vals[i], i, f"  validation x{r['validation_ratio']:.3f}, t={r['t']:.1f}", fontsize=7, va="center")
    ax.set_yticks(range(len(rows)), labels, fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("screen score: linearised drop of the training objective (fraction; higher is better)")
    ax.set_title("candidates on top of the nominal re-fit, best score first\n(blue: named, orange: fitted, not named)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def residual_vs_velocity(path, v, before, after, joint, unit_force, unit_vel):
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    k = max(1, len(v) // 4000)
    ax.plot(v[::k], before[::k], ".", ms=2, alpha=0.4, color="C3", label="nominal")
    ax.plot(v[::k], after[::k], ".", ms=2, alpha=0.4, color="C0", label="fitted (static part)")
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel(f"velocity of {joint} [{unit_vel}]")
    ax.set_ylabel(f"inverse-dynamics residual [{unit_force}]")
    ax.set_title("residual vs velocity (a step at 0: Coulomb friction; a slope: viscous)", fontsize=9)
    ax.legend(fontsize=7, markerscale=4)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def regimes_plot(path, regimes: dict, units: dict[str, str]):
    """Inverse-dynamics residual RMS per motion regime, one panel per joint, nominal vs fitted
    model, in the joint's force unit (lower is better). Absolute RMS rather than ratios: a ratio to
    the overall RMS makes a joint whose residual is tiny everywhere look as wrong as one whose
    residual is large; the dashed line is the nominal model's overall RMS for reference."""
    joints = list(regimes)[:6]
    fig, axes = plt.subplots(1, len(joints), figsize=(max(3.4 * len(joints) + 0.6, 6.0), 3.6), squeeze=False)
    for ax, joint in zip(axes[0], joints):
        t = {n: r for n, r in regimes[joint].items() if r.get("rms") is not None}
        names = list(t)
        x = np.arange(len(names))
        nom = [t[n]["rms"] for n in names]
        fit = [t[n].get("rms_fitted", np.nan) for n in names]
        ax.bar(x - 0.2, nom, 0.4, color="C3", label="nominal model")
        ax.bar(x + 0.2, fit, 0.4, color="C0", label="fitted model")
        overall = [r["rms"] / r["excess"] for r in t.values() if r.get("excess")]
        if overall:
            ax.axhline(overall[0], color="C3", ls="--", lw=0.8, label="nominal, all samples")
        ax.set_xticks(x, [f"{n.replace('_', ' ')}\n{100 * t[n]['fraction']:.0f}% of samples" for n in names],
                      rotation=30, fontsize=6.5, ha="right")
        top = max([v for v in nom + fit if np.isfinite(v)] + [overall[0] if overall else 0.0, 1e-12])
        ax.set_ylim(0, 1.35 * top)  # room for the legend above the bars
        ax.set_ylabel(f"residual RMS [{units.get(joint, '')}]", fontsize=8)
        ax.set_title(joint, fontsize=9)
        ax.tick_params(labelsize=7)
    axes[0, 0].legend(fontsize=6.5, ncol=2, loc="upper center")
    fig.suptitle("inverse-dynamics residual by motion regime (RMS; lower is better)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def correlation_plot(path, names: list[str], matrix: list[list]):
    """The fitted parameters' correlation matrix (|r| near 1: the data trade one for the other)."""
    c = np.array([[np.nan if x is None else x for x in row] for row in matrix], float)
    n = len(names)
    fig, ax = plt.subplots(figsize=(2.8 + 0.55 * n, 1.9 + 0.45 * n))
    im = ax.imshow(c, cmap="RdBu_r", vmin=-1, vmax=1)
    for i in range(n):
        for j in range(n):
            if np.isfinite(c[i, j]):
                ax.text(j, i, f"{c[i, j]:.2f}", ha="center", va="center", fontsize=6.5,
                        color="white" if abs(c[i, j]) > 0.6 else "black")
    ax.set_xticks(range(n), names, rotation=60, ha="right", fontsize=7)
    ax.set_yticks(range(n), names, fontsize=7)
    fig.colorbar(im, ax=ax, fraction=0.04, label="correlation")
    ax.set_title("correlation of the fitted parameters' estimates", fontsize=9)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def heldout_animation(path, system, sh, tiles, pred_b, pred_a, traj_index, seconds: float = 5.0,
                      fps: float = 20.0, width: int = 240, height: int = 180) -> str:
    """A GIF of held-out segments, one after another: the measured motion beside the nominal and the
    fitted model's predictions (each prediction starts from the measured state at its segment's
    start, as the fit scores it; a cut between segments is a jump). At most ``seconds`` of them, in
    real time. Returns what it shows, in words."""
    import mujoco

    from sim2real.common.video import frames, gl_backend, write_video

    gl_backend()
    tr = sh.trajs[traj_index]
    joints = list(system.qpos_names)   # (position columns: a ball or free joint has several)
    qb = np.stack([_stitch(sh, pred_b, tiles, "qpos", k, traj_index) for k in range(len(joints))], 1)
    qa = np.stack([_stitch(sh, pred_a, tiles, "qpos", k, traj_index) for k in range(len(joints))], 1)
    step = max(int(round(1.0 / (fps * tr.dt))), 1)  # samples per frame
    starts = sorted(int(sh.tiles.local[s]) + 1 for s in tiles if sh.tiles.traj[s] == traj_index)
    idx, budget = [], int(seconds / tr.dt)
    for st in starts:
        seg = [i for i in range(st, min(st + sh.H, len(tr)), step) if np.isfinite(qa[i]).all() and np.isfinite(qb[i]).all()]
        idx += seg[: max(budget - step * len(idx), 0) // step]
    idx = np.asarray(idx)
    if len(idx) < 2:
        raise ValueError("no held-out predictions to animate")
    m = system.mj
    adr = np.arange(m.nq)

    def poses(q):
        out = np.tile(m.qpos0, (len(idx), 1))
        out[:, adr] = q[idx]
        return out

    # per position column: an angle's error in mrad, a length's in mm, a quaternion component's in 1e-3
    milli = ["mrad" if a else ("mm" if ":" not in c or c.rsplit(":", 1)[1] in "xyz" else "x 1e-3")
             for a, c in zip(system.angles, joints)]

    def captions(q):  # time, and the worst joint's distance from the measured pose
        out = []
        for i in idx:
            e = np.abs(q[i] - tr.q[i])
            k = int(np.argmax(e))
            out.append(f"t = {tr.time[i]:.2f} s" + ("" if q is tr.q else
                       f", {joints[k]} off by {e[k] * 1e3:.3g} {milli[k]}"))
        return out

    meas = poses(tr.q)
    panels = [frames(m, meas, width, height, "measured", captions=captions(tr.q))]
    panels += [frames(m, poses(q), width, height, f"{label} (ghost: measured)", ghost=meas, captions=captions(q))
               for q, label in ((qb, "nominal model"), (qa, "fitted model"))]
    write_video(path, np.concatenate(panels, axis=2), 1.0 / (tr.dt * step))
    n = len({st for st in starts for i in idx if st <= i < st + sh.H})
    return f"{tr.name}: {n} segments of {sh.H * tr.dt:.3g} s, real time"


def energy_plot(path: str, curves: dict) -> None:
    """The work the model misses along each check recording (J, from its mean) beside the work of
    the dissipation fitted to it (``energy.scan``): a slow loss shows as a drift that grows with time."""
    per = curves["per_recording"][:3]
    fig, axes = plt.subplots(len(per), 1, figsize=(8, 2.6 * len(per)), squeeze=False)
    for ax, name, c in zip(axes[:, 0], curves["recordings"], per):
        ax.plot(c["t"], c["missing"], color="k", lw=1.2, label="work the model misses")
        ax.plot(c["t"], c["explained"], color="tab:red", lw=1.2, ls="--", label=f"{curves['label']} (fitted)")
        ax.set_title(name, fontsize=9)
        ax.set_ylabel("work (J)")
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time (s)")
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figures(d, system, sh, tiles, pred_b, pred_a, trajs, n_train, out, invdyn_rows,
            animation: bool = True) -> dict[str, str]:
    from sim2real.sysid.diagnose import _signal_names

    names = _signal_names(sh)
    units = {}
    m = system.mj
    for j, jn in enumerate(system.joints):
        slide = m.jnt_type[j] == 2
        units[f"qpos:{jn}"] = "m" if slide else "rad"
        units[f"qvel:{jn}"] = "m/s" if slide else "rad/s"
        units[jn] = "N" if slide else "N m"
    for c in system.qpos_names:   # a ball or free joint's coordinates
        if ":" in c:
            units[f"qpos:{c}"] = "m" if c.rsplit(":", 1)[1] in "xyz" else "1"   # (a quaternion's components)
    for c in system.dof_names:
        if ":" in c:
            units[f"qvel:{c}"] = "m/s" if c.rsplit(":", 1)[1].startswith("v") else "rad/s"
    for a, an in enumerate(system.actuators):
        units[f"force:{an}"] = "N" if actuator_is_linear(system.mj, a) else "N m"
    images = {}
    ti = int(sh.tiles.traj[tiles[0]])
    overlay(os.path.join(out, "overlay.png"), sh, tiles, pred_b, pred_a, ti, names, units)
    images["Sim vs real on held-out data"] = "overlay.png"
    if animation:
        try:
            window = heldout_animation(os.path.join(out, "heldout.gif"), system, sh, tiles, pred_b, pred_a, ti)
            images[f"Sim vs real, animated ({window})"] = "heldout.gif"
        except Exception as e:  # noqa: BLE001  (no OpenGL here: the report goes on without it)
            d["notes"].append(f"heldout.gif was not drawn: {type(e).__name__}: {str(e).splitlines()[0]}")
    curves = (d.get("energy") or {}).get("curves")
    if curves:
        energy_plot(os.path.join(out, "energy.png"), curves)
        images["Work over whole recordings"] = "energy.png"
    steps_plot(os.path.join(out, "steps.png"), d["steps"])
    images["Forward selection"] = "steps.png"
    per_segment = d["fit"].get("per_segment_before")
    if per_segment and all(s.get("heldout_segments") for s in d["steps"]):
        segments_plot(os.path.join(out, "heldout_segments.png"), d["steps"], per_segment)
        images["Held-out error per segment"] = "heldout_segments.png"
    if d["effects"]:
        ranking_plot(os.path.join(out, "candidates.png"), d["effects"])
        images["Candidate screen"] = "candidates.png"
    corr = d.get("correlation", {})
    if len(corr.get("names", [])) >= 2:
        correlation_plot(os.path.join(out, "correlation.png"), corr["names"], corr["matrix"])
        images["Parameter correlation"] = "correlation.png"
    before, after = invdyn_rows
    m = system.mj
    j = int(np.argmax([np.sqrt(np.mean(before["r"][:, m.jnt_dofadr[k]] ** 2)) /
                       (np.std(before["act"][:, m.jnt_dofadr[k]]) + np.std(before["r"][:, m.jnt_dofadr[k]]) + 1e-12)
                       for k in range(m.njnt)]))
    dof = m.jnt_dofadr[j]
    slide = m.jnt_type[j] == 2
    residual_vs_velocity(os.path.join(out, "residual_vs_velocity.png"), before["v"][:, dof], before["r"][:, dof],
                         after["r"][:, dof], system.joints[j], "N" if slide else "N m", "m/s" if slide else "rad/s")
    images["Residual vs velocity"] = "residual_vs_velocity.png"
    regimes_plot(os.path.join(out, "regimes.png"), d["mismatch"]["regimes"], units)
    images["Residual by regime"] = "regimes.png"
    return images


def left_text(d: dict) -> str:
    """One sentence on what the kept model leaves unexplained on the check data (``fit.left``,
    ``diagnose.left_over``), for the report and the command line. ``**bold**`` marks the verdict."""
    left = d["fit"].get("left")
    if not left:
        return ""
    r, worst = left["ratio"], max(left["per_signal"].items(), key=lambda kv: kv[1], default=None)
    size = (f"{r:.3g}x what the sensor noise and the physics step alone leave ({left['level']:.3g} against "
            f"{left['floor']:.3g} per residual)")
    if left["unexplained"]:
        return (f"**Motion is left unexplained**: on the check data the model misfits by {size}"
                + (f", most on {worst[0]} ({worst[1]:.3g}x)" if worst else "")
                + f"; models that hold every physics of their plant nearly always stay under {left['limit']:g}x. Physics "
                  "outside the candidates searched, an effect on several joints at once, or a parameter "
                  "the fit could not reach" + (f"; or units: {left['units']}." if left.get("units") else "."))
    return (f"What is left on the check data is {size}, under {left['limit']:g}x, where models that hold every "
            "physics of their plant nearly always stay: no large motion is left unexplained (a smaller effect may "
            "still hide below what these recordings tell apart).")


def _fmt(v):
    return "" if v is None or (isinstance(v, float) and not np.isfinite(v)) else f"{v:.4g}"


def blocks(d: dict, images: dict[str, str]) -> list[tuple]:
    """The report's content once, as blocks both writers render: ``("h1"|"h2"|"h3"|"p", text)``,
    ``("table", header, rows)``, ``("list", items)``, ``("img", title, file)``. Text may hold
    ``**bold**`` and ``code`` spans."""
    fit = d["fit"]
    B = [("h1", f"Diagnosis of `{os.path.basename(d['model'])}`")]

    def named(rows):  # "`effect` at `target`, ..."
        return ", ".join(f"`{r['effect']}`" + (f" at `{r['target']}`" if r["target"] else "") for r in rows)

    if d["answer"] == "effects":
        B.append(("p", "**Missing physics found:** " + named(d["selected"]) + "."))
    elif d["answer"] == "none" and d.get("unconfirmed"):
        B.append(("p", "**No missing effect confirmed**: " + named(d["unconfirmed"])
                  + " predicted the validation segments better than the nominal model (re-fitted parameters "
                    "below), but not clearly enough to be named (notes)."))
    elif d["answer"] == "none":
        B.append(("p", "**No missing effect found**: the nominal model (re-fitted parameters below) predicts the data "
                       "as well as any candidate."))
    elif fit.get("left", {}).get("units"):
        B.append(("p", "**Inconclusive**: " + named(d["selected"]) + " fitted, but the recordings may be logged in "
                       "other units or conventions than the model's (below), and the fit may stand in for that."))
    else:
        B.append(("p", "**Inconclusive**: effects improved the training recordings but not the held-out ones (notes)."))
    if fit.get("left"):
        B.append(("p", left_text(d)))

    def ci(v, sd):  # a 95% interval from the fit's standard deviation, where it has one
        return "" if sd is None or not np.isfinite(sd) else f"[{v - 1.96 * sd:.4g}, {v + 1.96 * sd:.4g}]"

    for s in d["selected"]:
        B += [("h3", f"`{s['effect']}`" + (f" at `{s['target']}`" if s["target"] else "")),
              ("p", f"Validation error x{s['validation_ratio']:.3g} of the model before it (paired t = {s['t']:.1f}; "
                    "lower is better).")]
        rows = []
        for k, v in s["params"].items():
            sd = s["std"].get(k)
            rows.append([f"`{k}`", f"{v:.6g}" + (" (a bound: notes)" if k == s.get("at_bound") else ""),
                         "not identified (notes)" if k in s.get("unidentified", ()) else _fmt(sd),
                         ci(v, sd),
                         s.get("units", {}).get(k, "s" if k.endswith("seconds") else "")])
        B.append(("table", ["parameter", "value", "std", "95% interval", "unit"], rows))
        if s.get("note"):
            B.append(("p", s["note"]))
    B += [("h2", "Fit on held-out data"),
          ("p", f"Normalised RMSE of {fit['metric']}, mean over signals: **{fit['before']:.4g} -> {fit['after']:.4g}** "
                f"({fit['change']}), on {', '.join(fit['recordings'])}."),
          ("table", ["signal", "before", "after"],
           [[sig, f"{v['before']:.4g}", f"{v['after']:.4g}"] for sig, v in fit["per_signal"].items()])]
    B += [("h2", "Steps"),
          ("p", "Each step is the model with the effects found so far and every nominal parameter re-fitted with "
                "them: `none` is the model file's own parameters re-fitted, so its held-out error is not the "
                "\"before\" above (the model file as written). `typical segment`: the median over held-out "
                "segments of each one's error against the step before (`none`: against the model file); a few "
                "segments no model predicts can raise the NRMSE while the rest fall. `kept`: what the held-out "
                "checks kept."),
          ("table", ["model", "training objective", "validation objective", "held-out NRMSE", "typical segment",
                     "kept"],
           [[s["model"], f"{s['objective']:.4g}", f"{s['validation']:.4g}", f"{s['heldout_nrmse']:.4g}",
             f"{s['heldout_typical_ratio']:.3g}x" if s.get("heldout_typical_ratio") is not None else "",
             "yes" if s["kept"] else "no"] for s in d["steps"]])]
    e = d.get("energy") or {}
    if e.get("candidates"):
        verdict = (f"named: `{e['named']}`" if e.get("named") else e.get("rejected", "nothing explains "
                   f"{100 * e['explained_needed']:.0f}% of the missing work on every check recording"))
        B += [("h2", "Work over whole recordings (slow dissipation)"),
              ("p", "The work each dissipation would do along the measured motion, against the work the model "
                    f"misses (fraction explained per check recording); {verdict}."
                    + (" Left out as glitches (0.1 s blocks no dissipation comes near): " + ", ".join(
                        f"{k} {v:g} s" for k, v in e["glitch_seconds"].items() if v) + "."
                       if any((e.get("glitch_seconds") or {}).values()) else "")),
              ("table", ["effect", "target", "size", "std", "explained", "held-out NRMSE"],
               [[c["effect"], c["target"], f"{c['value']:.4g} {c['unit']}", _fmt(c["std"]),
                 ", ".join(f"{x:.2f}" for x in c["explained"]),
                 f"{c['heldout_nrmse']:.4g}" if c.get("heldout_nrmse") is not None else ""] for c in e["candidates"]])]
    B += [("h2", "Nominal parameters re-fitted"),
          ("table", ["parameter", "nominal", "fitted", "std", "95% interval", "unit"],
           [[f"`{n}`", f"{v['nominal']:.6g}", f"{v['fitted']:.6g}", "held" if v["std"] is None else _fmt(v["std"]),
             ci(v["fitted"], v["std"]), v["unit"]]
            for n, v in d["nominal_refit"].items()])]
    if d["notes"]:
        B += [("h2", "Notes"), ("list", list(d["notes"]))]
    B.append(("p", f"Fitted MJCF: `{d['fitted_mjcf']}`" if d["fitted_mjcf"] else "Fitted MJCF: not written (notes)."))
    B += [("h2", "Where the nominal model is wrong"),
          ("table", ["signal", "NRMSE", "offset ratio"],
           [[sig, f"{v['nrmse']:.4g}", f"{v['offset_ratio']:.2f}"] for sig, v in d["mismatch"]["signals"].items()]),
          ("p", "Worst segments:"),
          ("list", [f"{w['recording']} {w['t_start']:.2f}-{w['t_end']:.2f} s, {w['signal']}: NRMSE {w['nrmse']:.3g}"
                    for w in d["mismatch"]["worst_windows"][:5]])]
    B += [("h2", "Candidates (first round)"),
          ("p", "Screen score: linearised drop of the training objective on top of the nominal re-fit; the best were "
                "fitted and judged on the validation segments (ratio to the model before; lower is better)."),
          ("table", ["effect", "target", "screen score", "validation ratio", "t", "named"],
           [[r["effect"], r["target"], f"{r['screen_score']:.4f}", _fmt(r.get("validation_ratio")), _fmt(r.get("t")),
             "yes" if r.get("passed") else ""] for r in d["effects"]])]
    for title, img in images.items():
        B += [("h2", title), ("img", title, img)]
    return B


def markdown(path: str, d: dict, images: dict[str, str]) -> None:
    """``report.md`` (figures linked by relative path)."""
    L = []
    for b in blocks(d, images):
        kind = b[0]
        if kind in ("h1", "h2", "h3"):
            L += ["#" * int(kind[1]) + " " + b[1], ""]
        elif kind == "p":
            L += [b[1], ""]
        elif kind == "table":
            L += ["| " + " | ".join(b[1]) + " |", "|" + "---|" * len(b[1])]
            L += ["| " + " | ".join(map(str, r)) + " |" for r in b[2]] + [""]
        elif kind == "list":
            L += [f"- {x}" for x in b[1]] + [""]
        elif kind == "img":
            L += [f"![{b[1]}]({b[2]})", ""]
    with open(path, "w") as f:
        f.write("\n".join(L))


def _inline(text: str) -> str:
    import html
    import re

    t = html.escape(text)
    t = re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", t)
    return re.sub(r"`(.+?)`", r"<code>\1</code>", t)


def html_page(path: str, d: dict, images: dict[str, str]) -> None:
    """``report.html``: the same content as one self-contained page, figures embedded (base64), so
    it can be mailed or attached without its folder."""
    import base64
    import html

    folder = os.path.dirname(path)
    H = []
    for b in blocks(d, images):
        kind = b[0]
        if kind in ("h1", "h2", "h3", "p"):
            H.append(f"<{kind}>{_inline(b[1])}</{kind}>")
        elif kind == "table":
            H.append("<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in b[1]) + "</tr>"
                     + "".join("<tr>" + "".join(f"<td>{_inline(str(c))}</td>" for c in r) + "</tr>" for r in b[2])
                     + "</table>")
        elif kind == "list":
            H.append("<ul>" + "".join(f"<li>{_inline(x)}</li>" for x in b[1]) + "</ul>")
        elif kind == "img":
            file = os.path.join(folder, b[2])
            if os.path.exists(file):
                with open(file, "rb") as f:
                    data = base64.b64encode(f.read()).decode()
                mime = "image/gif" if file.endswith(".gif") else "image/png"
                H.append(f'<figure><img alt="{html.escape(b[1])}" src="data:{mime};base64,{data}"></figure>')
            else:
                H.append(f"<p>(figure {html.escape(b[2])} not drawn)</p>")
    style = ("body{font-family:system-ui,sans-serif;max-width:1000px;margin:2em auto;padding:0 1em;color:#222}"
             "table{border-collapse:collapse;margin:.5em 0 1em}td,th{border:1px solid #ccc;padding:3px 8px;"
             "text-align:right}th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}"
             "code{background:#f4f4f4;padding:0 3px}img{max-width:100%}")
    title = html.escape(f"Diagnosis of {os.path.basename(d['model'])}")
    with open(path, "w") as f:
        f.write(f"<!doctype html><html><head><meta charset='utf-8'><title>{title}</title><style>{style}</style>"
                f"</head><body>{''.join(H)}</body></html>\n")
