"""The bundled real datasets diagnosed again and compared with their committed results.

    python benchmarks/real_datasets.py                     # every run; exits 1 if any result moved
    python benchmarks/real_datasets.py only=dfki,emps      # runs whose name contains one of these
    python benchmarks/real_datasets.py write=true          # the committed folders replaced by the reruns

The README's table of real recordings quotes the folders in ``benchmarks/results/real_datasets/``.
A change to the diagnosis can move what those runs give without touching any test (it happened:
the IBM and KUKA rows of 2026-11-26 and 12-04 were no longer reproduced by the code of 12-07), so
this script runs each split again on the defaults (the ``torque_offset`` runs also search the
offset) and prints, beside each committed ``diagnosis.json``: the answer, the effects named in
order with their fitted values, and the held-out error before and after. A run *moved* when its
named effects or targets differ, or a fitted value or held-out error differs by more than ``tol``
(relative). The reruns go to ``out`` (each a diagnosis folder) and the comparison to
``out/drift.md``. Runs take 10 s (EMPS, DFKI) to 5 min (KUKA, 7 joints) on 2 CPU cores; all nine,
about 20 minutes.
"""
from __future__ import annotations

import dataclasses
import json
import os
import sys
import time

from sim2real.common.cli import settings

import diagnosis_independent

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
COMMITTED = os.path.join(HERE, "results", "real_datasets")
D = "sim2real/sysid/data/"


@dataclasses.dataclass(frozen=True)
class Run:
    """One split of a bundled dataset: the model, the recordings fitted, those held out (paths
    relative to the repository's root), and effects searched besides the defaults."""
    model: str
    recordings: tuple[str, ...]
    heldout: tuple[str, ...]
    also: tuple[str, ...] = ()
    plots: bool = True


def _runs() -> dict[str, Run]:
    from sim2real.sysid import emps

    rel = lambda p: os.path.relpath(p, ROOT)  # noqa: E731
    dfki, ibm, kuka = D + "dfki_pendulum/", D + "ibm_double_pendulum/", D + "kuka_lwr4/"
    return {
        "emps": Run(rel(emps.NOMINAL_XML), (rel(emps.RECORDINGS["estimation"]),), (rel(emps.RECORDINGS["validation"]),)),
        "dfki_pendulum": Run(dfki + "pendulum.xml", (dfki + "energy_shaping.csv",), (dfki + "sac.csv",)),
        "dfki_pendulum_swapped": Run(dfki + "pendulum.xml", (dfki + "sac.csv",), (dfki + "energy_shaping.csv",)),
        "dfki_pendulum_torque_offset": Run(dfki + "pendulum.xml", (dfki + "energy_shaping.csv",), (dfki + "sac.csv",),
                                           ("torque_offset",), plots=False),
        "ibm_double_pendulum": Run(ibm + "double_pendulum.xml", (ibm + "run0.csv", ibm + "run1.csv"), (ibm + "run2.csv",)),
        "ibm_double_pendulum_swapped": Run(ibm + "double_pendulum.xml", (ibm + "run1.csv", ibm + "run2.csv"),
                                           (ibm + "run0.csv",)),
        "kuka_lwr4": Run(kuka + "kuka_lwr4.xml", (kuka + "run1.csv", kuka + "run2.csv"), (kuka + "run3.csv",)),
        "kuka_lwr4_swapped": Run(kuka + "kuka_lwr4.xml", (kuka + "run3.csv",), (kuka + "run1.csv",)),
        "kuka_lwr4_torque_offset": Run(kuka + "kuka_lwr4.xml", (kuka + "run1.csv", kuka + "run2.csv"),
                                       (kuka + "run3.csv",), ("torque_offset",), plots=False),
    }


def summary(d: dict) -> dict:
    """What the README quotes of a ``diagnosis.json``: the answer, the named effects in order
    (``effect@target`` -> fitted values), the held-out error before and after."""
    named = {}
    for s in d.get("selected", []):
        if s["effect"] != "none":
            named[f"{s['effect']}@{s['target']}"] = {k: float(v) for k, v in s["params"].items()}
    fit = d.get("fit") or {}
    return {"answer": d.get("answer"), "named": named, "before": fit.get("before"), "after": fit.get("after")}


def _g(x) -> str:
    return "?" if x is None else f"{x:.4g}"


def _rel(a, b) -> float:
    if a is None or b is None:
        return 0.0 if a is b else float("inf")
    a, b = float(a), float(b)
    return abs(a - b) / max(abs(a), abs(b), 1e-12)


def compare(old: dict, new: dict, tol: float) -> list[str]:
    """Why ``new`` (a ``summary``) differs from ``old`` beyond ``tol``; empty if it does not."""
    why = []
    if old["answer"] != new["answer"]:
        why.append(f"answer {old['answer']} -> {new['answer']}")
    if list(old["named"]) != list(new["named"]):
        why.append(f"named {', '.join(old['named']) or 'nothing'} -> {', '.join(new['named']) or 'nothing'}")
    else:
        for key, vals in old["named"].items():
            for p, v in vals.items():
                w = new["named"][key].get(p)
                if _rel(v, w) > tol:
                    why.append(f"{key} {p} {_g(v)} -> {_g(w)}")
    for k in ("before", "after"):
        if _rel(old[k], new[k]) > tol:
            why.append(f"held-out {k} {_g(old[k])} -> {_g(new[k])}")
    return why


def _line(s: dict) -> str:
    named = "; ".join(f"{k} " + ", ".join(f"{p}={_g(v)}" for p, v in vals.items()) for k, vals in s["named"].items())
    return f"{s['answer']}: {named or 'nothing named'}; held-out {_g(s['before'])} -> {_g(s['after'])}"


@dataclasses.dataclass
class Settings:
    """only: runs whose name contains one of these (comma-separated; empty: all); out: where the
    reruns go; tol: relative difference of a fitted value or held-out error counted as a move;
    write: replace the committed folders by the reruns (the README's table then needs updating);
    plots: figures in the reruns (``write`` draws them for the runs that had them)."""
    only: str = ""
    out: str = os.path.join("runs", "real_datasets")
    tol: float = 0.02
    write: bool = False
    plots: bool = False


def main(args: Settings) -> int:
    from sim2real.envs import parallel
    from sim2real.sysid import shooting

    try:  # the physics vectors of a call split over the cores, as the diagnose command does
        parallel.use_cpu_cores(min(parallel.cpu_cores(), shooting.B))
    except RuntimeError:  # JAX already running (a test calling main): its devices as they are
        pass
    out = os.path.abspath(args.out)
    cwd = os.getcwd()
    os.chdir(ROOT)  # the runs' paths, and so their diagnosis.json, are relative to the repository
    try:
        return _rerun(args, out)
    finally:
        os.chdir(cwd)


def _rerun(args: Settings, out: str) -> int:
    from sim2real.sysid.diagnose import DiagnoseConfig, diagnose  # (after the cores are declared)

    runs = _runs()
    chosen = [n for n in runs if not args.only or any(o and o in n for o in args.only.split(","))]
    if not chosen:
        raise SystemExit(f"only={args.only}: no run's name contains it; the runs: {', '.join(runs)}")
    lines, moved = [f"# Real datasets rerun ({time.strftime('%Y-%m-%d %H:%M')}, commit {diagnosis_independent._commit()}, tol {args.tol:g})", ""], []
    for name in chosen:
        run = runs[name]
        folder = os.path.join(COMMITTED if args.write else out, name)
        committed = os.path.join(COMMITTED, name, "diagnosis.json")
        old = None
        if os.path.exists(committed):
            with open(committed) as f:
                old = summary(json.load(f))
        cfg = DiagnoseConfig(model=run.model, recordings=run.recordings, heldout=run.heldout, out=folder,
                             overwrite=True, plots=run.plots and (args.write or args.plots), progress=False)
        if run.also:
            cfg = dataclasses.replace(cfg, effects=tuple(cfg.effects) + run.also)
        t0 = time.time()
        new = summary(diagnose(cfg))
        if args.write and os.path.exists(os.path.join(folder, "report.html")):
            # the one page repeats report.md with its figures embedded (about 1 MB a run): the
            # committed folders keep the figures once (docs/real_recordings.md)
            os.remove(os.path.join(folder, "report.html"))
        why = compare(old, new, args.tol) if old else ["no committed result"]
        if why:
            moved.append(name)
        verdict = "moved: " + "; ".join(why) if why else "the same"
        block = [f"## {name} ({time.time() - t0:.0f} s): {verdict}", "",
                 f"- committed: {_line(old) if old else '-'}", f"- now:       {_line(new)}", ""]
        print("\n".join(block), flush=True)
        lines += block
    lines.append(f"{len(chosen) - len(moved)} of {len(chosen)} the same"
                 + (f"; moved: {', '.join(moved)}" if moved else "") + ".")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "drift.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print(lines[-1])
    return 1 if moved and not args.write else 0


if __name__ == "__main__":
    sys.exit(main(settings(Settings, sys.argv[1:])))
