"""Concealed-effects benchmark for the diagnosis tool (CPU).

Every case hides one effect of the library (or only re-scales nominal parameters: the
parameter-only cases, where the right answer is ``none``) in a "true" plant, records a training
and a held-out run with sensor noise (``sim2real.sysid.generator``), and runs the diagnosis on
the *nominal* MJCF and those recordings. Writes a CSV of the cases, the confusion table
(markdown and PNG) and prints the accuracy.

    python benchmarks/concealed_effects.py                      # all cases (~15 min on 2 cores)
    python benchmarks/concealed_effects.py only=pendulum      # cases whose label contains it
"""
from __future__ import annotations

import csv
import dataclasses
import hashlib
import os
import platform
import re
import sys
import tempfile
import time

from sim2real.common.cli import settings
from sim2real.envs.base import ASSETS
from sim2real.sysid.generator import SYSTEMS, Case, record

# (effect, target, {param: value}) per system; magnitudes are a few to tens of percent of the
# actuator's force range. Saturation limits are in actuator-force units (before the gear, as
# MuJoCo's forcerange): the motors' commands are within +-1 there.
EFFECT_CASES = {
    "pendulum": [
        ("coulomb_friction", "hinge", {"coulomb:hinge": 0.15}),
        ("coulomb_friction", "hinge", {"coulomb:hinge": 0.4, "coulomb_asym:hinge": 0.3}),
        ("viscous_damping", "hinge", {"viscous:hinge": 0.1}),
        ("viscous_damping", "hinge", {"viscous:hinge": 0.3}),
        ("joint_stiffness", "hinge", {"stiffness:hinge": 1.0}),
        ("sensor_offset", "hinge", {"sensor_offset:hinge": 0.1}),
        ("mass_offset", "pole", {"payload:pole": 0.3}),
        ("action_delay", "", {"action_delay": 2.0}),
        ("motor_lag", "motor", {"motor_lag:motor": 0.05}),
        ("actuator_saturation", "motor", {"saturation:motor": 1.2}),
        ("backlash", "motor", {"backlash:motor": 0.05}),
    ],
    "cartpole": [
        ("coulomb_friction", "slider", {"coulomb:slider": 1.0}),
        ("coulomb_friction", "hinge", {"coulomb:hinge": 0.01}),
        ("joint_stiffness", "slider", {"stiffness:slider": 5.0}),
        ("sensor_offset", "hinge", {"sensor_offset:hinge": 0.05}),
        ("action_delay", "", {"action_delay": 3.0}),
        ("motor_lag", "slide", {"motor_lag:slide": 0.04}),
        ("actuator_saturation", "slide", {"saturation:slide": 0.4}),
        ("backlash", "slide", {"backlash:slide": 0.02}),
    ],
    "arm2": [
        ("coulomb_friction", "shoulder", {"coulomb:shoulder": 0.8}),
        ("coulomb_friction", "elbow", {"coulomb:elbow": 0.4, "coulomb_asym:elbow": -0.3}),
        ("joint_stiffness", "elbow", {"stiffness:elbow": 2.0}),
        ("sensor_offset", "shoulder", {"sensor_offset:shoulder": 0.08}),
        ("mass_offset", "lower", {"payload:lower": 0.3}),
        ("action_delay", "", {"action_delay": 2.5}),
        ("motor_lag", "shoulder", {"motor_lag:shoulder": 0.03}),
        ("actuator_saturation", "elbow", {"saturation:elbow": 0.5}),
        ("backlash", "elbow", {"backlash:elbow": 0.04}),
    ],
    "prismatic": [
        ("coulomb_friction", "axis", {"coulomb:axis": 20.0}),
        ("coulomb_friction", "axis", {"coulomb:axis": 40.0, "coulomb_asym:axis": -0.15}),
        ("joint_stiffness", "axis", {"stiffness:axis": 300.0}),
        ("sensor_offset", "axis", {"sensor_offset:axis": 0.002}),
        ("action_delay", "", {"action_delay": 1.5}),
        ("motor_lag", "drive", {"motor_lag:drive": 0.003}),
        ("actuator_saturation", "drive", {"saturation:drive": 150.0}),
        ("backlash", "drive", {"backlash:drive": 0.0005}),
    ],
}
# parameter-only truths: nominal parameters off, nothing missing (the answer is ``none``)
NONE_CASES = {
    "pendulum": [{"mass:pole": 1.3}, {"mass:pole": 0.8}],
    "cartpole": [{"mass:cart": 1.3, "mass:pole": 0.12}, {"damping:slider": 0.05}],
    "arm2": [{"mass:upper": 1.3, "mass:lower": 0.5}, {"damping:shoulder": 0.1, "damping:elbow": 0.1}],
    "prismatic": [{"mass:carriage": 120.0}, {"damping:axis": 300.0}],
}


# position measurement noise (std): 0.1 mm / mrad, and for the prismatic drive an encoder like
# EMPS's (steps of 5e-8 m); 1e-4 m there would be 137 N of servo-force noise (Kp = 1.37e6 N/m)
NOISE = {"pendulum": 1e-4, "cartpole": 1e-4, "arm2": 1e-4, "prismatic": 1e-6}


def cases() -> list[Case]:
    out = []
    for system, rows in EFFECT_CASES.items():
        for k, (effect, target, values) in enumerate(rows):
            out.append(Case(system, effect, target, tuple(values.items()), noise=NOISE[system], seed=k))
    for system, rows in NONE_CASES.items():
        for k, nominal in enumerate(rows):
            out.append(Case(system, "none", "", (), tuple(nominal.items()), noise=NOISE[system], seed=100 + k))
    return out


def run_case(case: Case, work: str) -> dict:
    from sim2real.sysid.diagnose import DiagnoseConfig, diagnose

    tag = case.label.replace("/", "_").replace("@", "_")
    train = os.path.join(work, f"{tag}_train.csv")
    held = os.path.join(work, f"{tag}_heldout.csv")
    truth = record(case, train)
    record(dataclasses.replace(case, seed=case.seed + 1000), held)
    xml = os.path.join(ASSETS, SYSTEMS[case.system][0])
    t0 = time.time()
    d = diagnose(DiagnoseConfig(model=xml, recordings=(train,), heldout=(held,), out=os.path.join(work, tag),
                                overwrite=True, plots=False, progress=False))
    sel = d["selected"][0] if d["selected"] else {"effect": "none", "target": "", "params": {}}
    return {"case": case.label, "system": case.system, "true_effect": case.effect, "true_target": case.target,
            "truth": ";".join(f"{k}={v:g}" for k, v in truth.items()),
            "named_effect": sel["effect"], "named_target": sel["target"],
            "named_params": ";".join(f"{k}={v:.4g}" for k, v in sel["params"].items()),
            "also_named": " + ".join(f"{s['effect']}@{s['target']}" for s in d["selected"][1:]),
            "answer": d["answer"],
            "heldout_before": round(d["fit"]["before"], 5), "heldout_after": round(d["fit"]["after"], 5),
            # first round: every candidate's screen score, and the fitted ones' validation ratio
            "candidates": " ".join(f"{e['effect']}@{e['target']}:{e['screen_score']:.3f}:{e.get('validation_ratio', float('nan')):.3g}"
                                   for e in d["effects"]),
            "correct": _matches(case, sel) and len(d["selected"]) <= 1,
            "truth_tied": not _matches(case, sel) and any(_matches(case, r) for r in d["indistinguishable"]),
            "seconds": round(time.time() - t0, 1)}


def _matches(case: Case, effect_row: dict) -> bool:
    """The diagnosis' effect row names the hidden effect (at its target; delay has none)."""
    return effect_row["effect"] == case.effect and (case.effect in ("none", "action_delay")
                                                    or effect_row["target"] == case.target)


def confusion(rows: list[dict]) -> tuple[list[str], list[list[int]]]:
    labels = sorted({r["true_effect"] for r in rows} | {r["named_effect"] for r in rows})
    mat = [[sum(1 for r in rows if r["true_effect"] == t and r["named_effect"] == n) for n in labels] for t in labels]
    return labels, mat


@dataclasses.dataclass
class Settings:
    """only: run the cases whose label contains this text; out: results folder."""
    only: str = ""
    out: str = os.path.join(os.path.dirname(__file__), "results", "concealed_effects")


def _cpu_tag() -> str:
    """A short hash of this CPU's model and instruction-set flags (Linux), else of its platform name."""
    lines = []
    if os.path.exists("/proc/cpuinfo"):
        with open("/proc/cpuinfo") as f:
            lines = [ln for ln in f.read().split("\n\n")[0].splitlines() if ln.startswith(("flags", "model name"))]
    return hashlib.sha1("".join([platform.machine(), platform.processor(), *lines]).encode()).hexdigest()[:12]


def main(args: Settings):
    import jax
    from rich.progress import Progress

    # every case builds its own System (new traces); the persistent cache skips re-compiling them.
    # One folder per CPU: XLA's key leaves the host's instruction set out, and a cache written on
    # another CPU (a VM moved to another host) loads code this one may not run (XLA warns: SIGILL)
    jax.config.update("jax_compilation_cache_dir", os.path.join(tempfile.gettempdir(), f"sim2real_jax_cache_{_cpu_tag()}"))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.5)
    todo = [c for c in cases() if args.only in c.label]
    os.makedirs(args.out, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as work, Progress() as bar:
        task = bar.add_task("cases", total=len(todo))
        for case in todo:
            try:
                row = run_case(case, work)
            except Exception as e:  # a crash is a wrong answer, reported as such
                row = {"case": case.label, "system": case.system, "true_effect": case.effect,
                       "true_target": case.target, "named_effect": f"error: {type(e).__name__}: {e}"[:200],
                       "correct": False}
            rows.append(row)
            bar.console.print(f"{row['case']:45s} -> {row['named_effect']}@{row.get('named_target', '')} "
                              f"{'OK' if row['correct'] else 'WRONG'}  {row.get('named_params', '')}")
            bar.advance(task)
    suffix = "_" + re.sub(r"[^A-Za-z0-9@_.-]", "_", args.only) if args.only else ""  # only=pendulum/none: one file
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(os.path.join(args.out, f"cases{suffix}.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, keys)
        w.writeheader()
        w.writerows(rows)
    n_ok = sum(r["correct"] for r in rows)
    none_rows = [r for r in rows if r["true_effect"] == "none"]
    false_named = sum(r["named_effect"] != "none" for r in none_rows)
    n_tied = sum(bool(r.get("truth_tied")) for r in rows)
    labels, mat = confusion(rows)
    lines = [f"Concealed effects: {n_ok}/{len(rows)} named correctly ({100 * n_ok / max(len(rows), 1):.0f}%); "
             f"effects named in parameter-only cases: {false_named}/{len(none_rows)}; "
             f"wrong but with the true effect reported as indistinguishable from the named one: {n_tied}.", "",
             "| true \\ named | " + " | ".join(labels) + " |", "|---" * (len(labels) + 1) + "|"]
    lines += [f"| {t} | " + " | ".join(str(v) if v else "." for v in row) + " |" for t, row in zip(labels, mat)]
    with open(os.path.join(args.out, f"confusion{suffix}.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, ax = plt.subplots(figsize=(1.0 + 0.55 * len(labels), 0.8 + 0.5 * len(labels)))
    a = np.array(mat, float)
    ax.imshow(a, cmap="Blues")
    for i in range(len(labels)):
        for j in range(len(labels)):
            if a[i, j]:
                ax.text(j, i, int(a[i, j]), ha="center", va="center", color="white" if a[i, j] > a.max() / 2 else "k")
    ax.set_xticks(range(len(labels)), labels, rotation=60, ha="right")
    ax.set_yticks(range(len(labels)), labels)
    ax.set_xlabel("named by the diagnosis")
    ax.set_ylabel("hidden in the true plant")
    ax.set_title(f"{n_ok}/{len(rows)} correct")
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, f"confusion{suffix}.png"), dpi=120)


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
