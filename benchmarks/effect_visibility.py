"""How visible each independent benchmark case's hidden physics is, and the diagnosis' answers by it.

    python benchmarks/effect_visibility.py split=extra results=extra_step64_device jobs=2

Per case, ``sysid_cases.visibility``: the RMS change the hidden effects make to 1 s position
predictions from the plant's true state, in units of the sensor's precision (native MuJoCo, the
generator's own code; nothing from ``sim2real`` runs). It says how much the data can show, not
what the diagnosis found, so it may be computed for a test list without a look at it: the
answers it is set beside are the ones a results folder already holds.

Writes ``<out>/<split>.csv`` (case, visibility) once per list (kept: a list is frozen) and, with
``results=`` (a folder of ``diagnosis_independent.py`` under ``benchmarks/results/
diagnosis_independent/``, or a path), ``<out>/<results folder>.md``: the answers' accuracy per
visibility band, single effects and pairs apart, and the missed cases with their visibility.
"""
from __future__ import annotations

import csv
import dataclasses
import os
import sys

import numpy as np

from sim2real.common.cli import settings

import sysid_cases

HERE = os.path.dirname(os.path.abspath(__file__))
RESULTS = os.path.join(HERE, "results", "diagnosis_independent")
BANDS = (0.0, 3.0, 10.0, 30.0, np.inf)  # visibility bands of the tables (x the sensor's precision)


@dataclasses.dataclass
class Settings:
    """split: which list (as ``diagnosis_independent.py``); results: a results folder of that list
    to tabulate (a name under ``benchmarks/results/diagnosis_independent/`` or a path; empty: only
    the visibilities); seconds: the prediction horizon (s); jobs: processes; out: where to write."""
    split: str = "extra"
    results: str = ""
    seconds: float = 1.0
    jobs: int = 1
    out: str = os.path.join(RESULTS, "visibility")


def _one(args: tuple) -> tuple[str, float]:
    case, seconds = args
    return case.label, sysid_cases.visibility(case, seconds)


def read(path: str) -> dict[str, float]:
    """``{case label: visibility}`` as ``visibilities`` wrote it."""
    with open(path) as f:
        return {r["case"]: float(r["visibility"]) for r in csv.DictReader(f)}


def visibilities(split: str, seconds: float, jobs: int, path: str) -> dict[str, float]:
    """``{case label: visibility}`` of a list, read from ``path`` if an earlier run wrote it."""
    if os.path.exists(path):
        return read(path)
    cases = [c for c in sysid_cases.split_cases(split) if c.effects]
    if not cases:
        raise SystemExit(f"split '{split}' has no case with a hidden effect")
    work = [(c, seconds) for c in cases]
    if jobs > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(jobs) as ex:
            rows = list(ex.map(_one, work))
    else:
        rows = []
        for i, w in enumerate(work):
            rows.append(_one(w))
            print(f"[{i + 1}/{len(work)}] {rows[-1][0]}: {rows[-1][1]:.2f}", flush=True)
    tmp = path + ".part"  # a list's file appears whole or not at all
    with open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["case", "visibility"])
        w.writerows((k, f"{v:.4g}") for k, v in rows)
    os.replace(tmp, path)
    return dict(rows)


def table(rows: list[dict], vis: dict[str, float]) -> str:
    """Accuracy per visibility band (single effects and pairs), then the misses by visibility."""
    def band(v):
        i = int(np.searchsorted(BANDS, v, side="right")) - 1
        hi = BANDS[i + 1]
        return f"{BANDS[i]:g}-{hi:g}" if np.isfinite(hi) else f">= {BANDS[i]:g}"

    L = ["| visibility (x precision) | single effects named | pairs, both named |", "|---|---|---|"]
    for i in range(len(BANDS) - 1):
        lab = band(BANDS[i])
        cells = []
        for kind in ("single", "double"):
            rs = [r for r in rows if r["kind"] == kind and band(vis[r["case"]]) == lab]
            ok = sum(str(r["correct"]) == "True" for r in rs)  # (read back from a csv: text)
            cells.append(f"{ok}/{len(rs)}" + (f" ({100 * ok / len(rs):.0f}%)" if rs else ""))
        L.append(f"| {lab} | {cells[0]} | {cells[1]} |")
    missed = sorted((vis[r["case"]], r["case"], r["named"]) for r in rows
                    if r["kind"] != "none" and str(r["correct"]) != "True")
    L += ["", "Missed (visibility, case, named):", ""]
    L += [f"- {v:.2f}: {c} -> {n}" for v, c, n in missed]
    return "\n".join(L) + "\n"


def main(args: Settings) -> dict[str, float]:
    os.makedirs(args.out, exist_ok=True)
    vis = visibilities(args.split, args.seconds, args.jobs, os.path.join(args.out, f"{args.split}.csv"))
    if args.results:
        folder = args.results if os.path.isdir(args.results) else os.path.join(RESULTS, args.results)
        path = os.path.join(folder, "cases.csv")
        if not os.path.exists(path):
            raise SystemExit(f"results '{args.results}': no cases.csv in {folder}")
        with open(path) as f:
            rows = [r for r in csv.DictReader(f) if r["kind"] != "none"]
        unknown = [r["case"] for r in rows if r["case"] not in vis]
        if unknown:
            raise SystemExit(f"{path}: case '{unknown[0]}' is not in the {args.split} list")
        name = os.path.basename(os.path.normpath(folder))
        text = (f"## {name}: answers by the hidden physics' visibility\n\n"
                f"Visibility: the RMS change the hidden effects make to {args.seconds:g} s position predictions "
                "from the true state, in units of the sensor's precision (`sysid_cases.visibility`).\n\n"
                + table(rows, vis))
        with open(os.path.join(args.out, f"{name}.md"), "w") as f:
            f.write(text)
        print(text)
    return vis


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
