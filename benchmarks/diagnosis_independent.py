"""Independent benchmark of the diagnosis: cases from ``sysid_cases.py`` (native MuJoCo truth,
effects implemented there, fresh MJCF), a tuning half and a frozen test half.

    python benchmarks/diagnosis_independent.py split=tuning          # what thresholds may look at
    python benchmarks/diagnosis_independent.py split=test            # the first test half (each run is logged)
    python benchmarks/diagnosis_independent.py split=fresh jobs=2    # the second, fresh test list (logged)
    python benchmarks/diagnosis_independent.py split=tuning only=arm2 jobs=2

Per case: 2 training recordings and 1 held-out recording; the diagnosis runs on its defaults with
the nominal MJCF. Writes ``<out>/<split>/cases.csv`` (one row per case), ``summary.md`` (the
figures, confusion table and per-condition accuracy) and, for a test list (``test``, ``fresh``),
appends the run to ``test_split_looks.md`` or ``fresh_split_looks.md``.

Scoring: a single-effect case counts as *named* when the diagnosis selects exactly the hidden
effect at its target (nothing else); a two-effect case when it selects both (and nothing else);
a parameter-only case when it selects no effect. Parameters are compared with the truth's
(delay in seconds, Coulomb level, payload mass, ...): within 25%.
"""
from __future__ import annotations

import csv
import dataclasses
import json
import os
import sys
import time
import traceback
from typing import Any, Literal

import numpy as np

from sim2real.common.cli import settings
from sim2real.envs.parallel import cpu_cores

import sysid_cases

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "diagnosis_independent")


def _key(effect: str, target: str) -> str:
    return effect if effect in ("action_delay", "none") else f"{effect}@{target}"


def truth_keys(case: sysid_cases.Case) -> set[str]:
    return {_key(e, t) for e, t, _ in case.effects}


def _selected(d: dict) -> list[dict]:
    sel = d.get("selected", [])
    return [d["effects"][0]] if isinstance(sel, str) else sel  # (diagnosis.json before the list)


def named_keys(d: dict) -> list[str]:
    return [_key(s["effect"], s["target"]) for s in _selected(d) if s["effect"] != "none"]


def _param_errors(desc: dict, d: dict) -> dict[str, float]:
    """Relative error of each named true effect's main parameter."""
    out = {}
    dt = float(d.get("sample_period", 0.0))
    for sel in _selected(d):
        k = _key(sel["effect"], sel["target"])
        tv = desc["truth_values"].get(k)
        if not tv:
            continue
        for name, true in tv.items():
            if name == "action_delay_seconds":
                got = sel["params"].get("action_delay_seconds")
                if got is None and "action_delay" in sel["params"]:
                    got = sel["params"]["action_delay"] * dt
            else:
                got = sel["params"].get(name)
            if got is not None and true:
                out[k] = abs(float(got) - float(true)) / abs(float(true))
    return out


def case_files(case: sysid_cases.Case, folder: str) -> dict:
    """The case's recordings and ``truth.json`` in ``folder`` (made again unless those there are of
    this case's design and this generator's version); returns the truth's description."""
    desc_path = os.path.join(folder, "truth.json")
    if os.path.exists(desc_path):
        with open(desc_path) as f:
            desc = json.load(f)
        if (desc.get("design") == dataclasses.asdict(case.design)
                and desc.get("generator_version") == sysid_cases.GENERATOR_VERSION):
            return desc
    return sysid_cases.generate(case, folder)


def run_case(case: sysid_cases.Case, work: str, settings: dict | None = None) -> dict:
    from sim2real.sysid.diagnose import DiagnoseConfig, diagnose

    folder = os.path.join(work, case.label)
    desc = case_files(case, folder)
    row = {"case": case.label, "seed": case.seed, "split": case.split, "kind": case.kind, "system": case.system,
           "truth": " + ".join(sorted(truth_keys(case))) or "none",
           **{f"design_{k}": v for k, v in dataclasses.asdict(case.design).items()}}
    t0 = time.time()
    try:
        d = diagnose(DiagnoseConfig(model=os.path.join(folder, "nominal.xml"),
                                    recordings=(os.path.join(folder, "train_0.csv"), os.path.join(folder, "train_1.csv")),
                                    heldout=(os.path.join(folder, "heldout.csv"),),
                                    out=os.path.join(folder, "diagnosis"), overwrite=True, plots=False, progress=False,
                                    **(settings or {})))
    except Exception as e:  # noqa: BLE001  (a crash is a wrong answer, reported as such)
        row.update(named="error", answer=f"error: {type(e).__name__}: {e}"[:300], correct=False,
                   seconds=round(time.time() - t0, 1), traceback=traceback.format_exc()[-600:])
        return row
    named = named_keys(d)
    truth = truth_keys(case)
    errs = _param_errors(desc, d)
    row.update(named=" + ".join(named) or "none", answer=d.get("answer", ""),
               correct=set(named) == truth, truth_among_named=bool(truth) and truth <= set(named),
               n_true_named=len(truth & set(named)), false_named=len(set(named) - truth),
               param_errors=";".join(f"{k}={v:.3f}" for k, v in errs.items()),
               params_within_25=all(v <= 0.25 for v in errs.values()) if errs else "",
               heldout_before=d["fit"]["before"], heldout_after=d["fit"]["after"],
               never_worse=d["fit"]["after"] <= d["fit"]["before"] * (1 + 1e-9),
               seconds=round(time.time() - t0, 1), diag_seconds=d.get("seconds"))
    return row


def ran_on(jobs: int, devices: int) -> str:
    """What the cases ran on, for the summary's time line (called after the runs: JAX may start
    here then). The diagnosis simulates on JAX's default backend: a GPU where there is one."""
    import jax

    if jax.default_backend() == "cpu":
        return f"{cpu_cores()} CPU cores, {jobs} case(s) at a time, {devices} XLA CPU device(s) each"
    return f"one {jax.devices()[0].device_kind} ({jax.default_backend()}), {jobs} case(s) at a time"


def summarise(rows: list[dict], title: str, where: str) -> str:
    """The figures, confusion table and per-condition accuracy; ``where``: what the cases ran on
    (``ran_on``)."""
    def pct(a, b):
        return f"{a}/{b} ({100 * a / b:.0f}%)" if b else "0/0"

    single = [r for r in rows if r["kind"] == "single"]
    double = [r for r in rows if r["kind"] == "double"]
    none = [r for r in rows if r["kind"] == "none"]
    named_rows = [r for r in rows if r.get("params_within_25") not in ("", None)]
    L = [f"## {title}", "",
         f"- single effects named (exactly, nothing else): **{pct(sum(bool(r['correct']) for r in single), len(single))}**"
         f" (the true effect among those named: {pct(sum(bool(r.get('truth_among_named')) for r in single), len(single))})",
         f"- two-effect cases with both named: **{pct(sum(bool(r['correct']) for r in double), len(double))}** "
         f"(both among those named: {pct(sum(bool(r.get('truth_among_named')) for r in double), len(double))}; "
         f"at least one: {pct(sum((r.get('n_true_named') or 0) >= 1 for r in double), len(double))})",
         f"- parameter-only cases with an effect named: **{sum(r['named'] not in ('none',) for r in none)}/{len(none)}**",
         f"- held-out error never worse than the nominal model's: "
         f"**{pct(sum(r.get('never_worse') is True for r in rows), len(rows))}**",
         f"- named effects' parameters within 25% of the truth: **{pct(sum(r['params_within_25'] is True for r in named_rows), len(named_rows))}**",
         f"- seconds per case ({where}): median {np.median([r['seconds'] for r in rows]):.1f}, "
         f"max {np.max([r['seconds'] for r in rows]):.1f}; 8 s recordings: median "
         f"{np.median([r['seconds'] for r in rows if r['design_seconds'] == 8.0] or [np.nan]):.1f}, max "
         f"{np.max([r['seconds'] for r in rows if r['design_seconds'] == 8.0] or [np.nan]):.1f}",
         f"- errors (crashes): {sum(r['named'] == 'error' for r in rows)}", ""]
    # confusion over single-effect and parameter-only cases (effect kinds, targets ignored)
    kinds = lambda s: "none" if s in ("none", "") else ("error" if s == "error" else  # noqa: E731
                                                         " + ".join(sorted({x.split("@")[0] for x in s.split(" + ")})))
    conf_rows = single + none
    truths = sorted({kinds(r["truth"]) for r in conf_rows})
    nameds = sorted({kinds(r["named"]) for r in conf_rows})
    L += ["Confusion (single-effect and parameter-only cases; effect kinds):", "",
          "| true \\ named | " + " | ".join(nameds) + " |", "|---" * (len(nameds) + 1) + "|"]
    for t in truths:
        cnt = [sum(1 for r in conf_rows if kinds(r["truth"]) == t and kinds(r["named"]) == n) for n in nameds]
        L.append(f"| {t} | " + " | ".join(str(c) if c else "." for c in cnt) + " |")
    L += ["", "Per condition (fraction of cases answered correctly):", "", "| condition | value | correct |", "|---|---|---|"]
    for key in ("design_integrator", "design_rate", "design_excitation", "design_mass_mode", "design_qvel", "system"):
        for v in sorted({str(r[key]) for r in rows}):
            sub = [r for r in rows if str(r[key]) == v]
            L.append(f"| {key.replace('design_', '')} | {v} | {pct(sum(bool(r['correct']) for r in sub), len(sub))} |")
    L.append("")
    return "\n".join(L)


@dataclasses.dataclass
class Settings:
    """split: which cases; only: cases whose label contains this text (several, comma-separated:
    any); work: where generated cases are kept; out: results root; tag: suffix of the results
    folder; jobs: processes; note: a line for the test-split log (why this look); diagnose:
    diagnosis settings other than the defaults
    (``diagnose.min_gain=0.01``; tuning runs only)."""
    split: Literal[("all",) + sysid_cases.SPLITS] = "tuning"
    only: str = ""
    work: str = os.path.join("runs", "sysid_cases")
    out: str = OUT
    tag: str = ""
    jobs: int = 1
    note: str = ""
    diagnose: dict[str, Any] = dataclasses.field(default_factory=dict)


def main(args: Settings):
    cases = [c for c in sysid_cases.split_cases(args.split) if any(o in c.label for o in args.only.split(","))]
    listed = sysid_cases.build_cases(fresh=args.split == "fresh")
    out = os.path.join(args.out, args.split + args.tag)
    options = dict(args.diagnose)
    if options and args.split in ("test", "fresh"):
        raise SystemExit(f"the {args.split} list is a test list: it is run with the defaults only")
    if args.split in ("test", "fresh") and not args.only and os.path.exists(os.path.join(out, "cases.csv")):
        # every look at a test list is kept: a second run names its own folder
        raise SystemExit(f"{out} holds an earlier look at the {args.split} list; give this one a tag= "
                         f"(e.g. tag=_third_look)")
    # each case's simulations over its share of the cores, as the diagnose command does. Only the
    # setting: JAX must not start here, as the workers fork from this process (a forked JAX
    # backend deadlocks); each starts its own with that many CPU devices.
    import jax

    devices = max(1, cpu_cores() // args.jobs)
    jax.config.update("jax_num_cpu_devices", devices)
    print(f"{len(cases)} cases (case list {sysid_cases.fingerprint(listed)}), {args.jobs} at a time, "
          f"{devices} CPU device(s) each", flush=True)
    os.makedirs(args.work, exist_ok=True)
    os.makedirs(out, exist_ok=True)
    rows = []
    t_start = time.time()
    if args.jobs > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(args.jobs) as ex:
            futs = [ex.submit(run_case, c, args.work, options) for c in cases]
            for f in futs:
                rows.append(f.result())
                _print(rows[-1])
    else:
        for c in cases:
            rows.append(run_case(c, args.work, options))
            _print(rows[-1])
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(os.path.join(out, "cases.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, keys)
        w.writeheader()
        w.writerows(rows)
    text = summarise(rows, f"{args.split} split ({len(rows)} cases{', only ' + args.only if args.only else ''})",
                     ran_on(args.jobs, devices))
    vis_path = os.path.join(OUT, "visibility", f"{args.split}.csv")
    if os.path.exists(vis_path):  # the list's visibilities, once computed (effect_visibility.py)
        import effect_visibility

        vis = effect_visibility.read(vis_path)
        text += ("\nBy the hidden physics' visibility (`effect_visibility.py`: x the sensor's precision):\n\n"
                 + effect_visibility.table([r for r in rows if r["kind"] != "none"], vis))
    with open(os.path.join(out, "summary.md"), "w") as f:
        f.write(text)
    print(text)
    if args.split in ("test", "fresh") and not args.only:
        log = os.path.join(args.out, f"{args.split}_split_looks.md")
        with open(log, "a") as f:
            f.write(f"- {time.strftime('%Y-%m-%d %H:%M')}: commit {_commit()}, {len(rows)} cases, "
                    f"{time.time() - t_start:.0f} s. {args.note}\n")


def _print(r):
    mark = "OK " if r.get("correct") else "-- "
    print(f"{mark}{r['case']:50s} named {r['named']:40s} {r.get('seconds', '')}s "
          f"{r.get('param_errors', '')} {r.get('answer', '')[:80]}", flush=True)


def _commit() -> str:
    try:
        import subprocess

        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              cwd=HERE).stdout.strip()
    except Exception:  # noqa: BLE001
        return "?"


if __name__ == "__main__":
    sys.exit(main(settings(Settings, sys.argv[1:])))
