"""Which of the diagnosis' misses the data could have told apart: an oracle check.

    python benchmarks/diagnosis_ceiling.py split=fresh results=fresh_eleventh_look
    python benchmarks/diagnosis_ceiling.py split=combos cases=LABELS.txt jobs=2

Per case (by default every case a results folder of ``diagnosis_independent.py`` holds as
missed): the diagnosis runs as the benchmark runs it, and after its selection the *true*
hypothesis -- the hidden effects, the generator's own list of them -- is fitted by the
diagnosis' own machinery (the nominal parameters and every effect parameter free, started at the
truth's values, from the nominal re-fit and from the model file's values, the better kept). It is
then judged against the answer's model on the validation segments by the selection's own test
(``Selector.judge``: validation error lower by ``min_gain``, paired t >= ``min_t``):

- ``truth passes``: the true hypothesis passes against the answer: the data favours it and the
  search did not reach it (a screen that left it out, a fit that stopped short): fixable.
- ``answer passes``: the answer passes against the truth: with this simulator the data favours
  the wrong hypothesis (an effect or integrator the diagnosis models differently, or noise).
- ``tie``: neither passes: these recordings, by this test, cannot tell the truth from the answer;
  no threshold of the selection names the truth here without naming the answer elsewhere alike.
- ``not searched``: a true effect is not among the diagnosis' candidates (e.g. a target the
  model gives no parameter for).

The held-out NRMSE of both models is written beside it. Nothing of the answer changes: the
diagnosis writes what it always writes, and the oracle's fits come after its selection. So this
may be run on a test list's misses without tuning anything on it; each run on a test list is
logged in ``<split>_split_looks.md`` all the same.

Writes ``<out>/<split><tag>.csv`` (one row per case) and ``.md`` (the counts per class, single
effects and pairs apart, and every row).
"""
from __future__ import annotations

import csv
import dataclasses
import json
import os
import sys
import time
from typing import Literal

import numpy as np

from sim2real.common.cli import settings
from sim2real.envs.parallel import cpu_cores

import diagnosis_independent as bench
import sysid_cases

OUT = os.path.join(bench.OUT, "ceiling")


MAX_STARTS = 6  # combinations of the true effects' other parameters tried (per base)


def true_start(candidate, values: dict, dt: float, tail: tuple | None = None) -> tuple:
    """The candidate's parameters at the truth's values: the truth gives the first (the delay in
    seconds, converted to samples of ``dt``); the others are ``tail``, or else those of the
    candidate's screening grid point nearest to it (a band's motor side, a payload's distance, a
    friction's onset)."""
    name = candidate.params[0]
    true = values.get(name)
    if true is None and name == "action_delay" and "action_delay_seconds" in values:
        true = values["action_delay_seconds"] / dt
    if true is None:
        raise KeyError(f"the truth gives no value for {name} ({sorted(values)})")
    if tail is None:
        tail = min(candidate.grid, key=lambda g: abs(np.log(max(g[0], 1e-12) / max(true, 1e-12))))[1:]
    lo = [r[0] for r in candidate.search]
    hi = [r[1] for r in candidate.search]
    return tuple(float(x) for x in np.clip((true,) + tuple(tail), lo, hi))


def classify(truth_vs_answer: tuple, answer_vs_truth: tuple, min_gain: float, min_t: float) -> str:
    """``(ratio, t)`` of each model judged against the other (``Selector.judge``) -> the class."""
    def passes(rt):
        return rt[0] <= 1 - min_gain and rt[1] >= min_t
    if passes(truth_vs_answer):
        return "truth passes"
    if passes(answer_vs_truth):
        return "answer passes"
    return "tie"


class _Oracle:
    """Wraps ``Selector.run`` for one diagnosis: after the selection it keeps the selector and its
    models (``capture``); ``judge`` then fits the true hypothesis (``labels``, ``values``: the
    truth's) and sets it against the answer."""

    def __init__(self, labels: list[str], values: dict):
        self.labels, self.values, self.out = labels, values, {}

    def __enter__(self):
        from sim2real.sysid import select

        self._orig = select.Selector.run
        oracle = self

        def run(sel):
            final, steps = oracle._orig(sel)
            try:
                oracle.capture(sel, final, steps)
            except Exception as e:  # noqa: BLE001  (recorded; the diagnosis itself goes on)
                oracle.out = {"status": f"error: {type(e).__name__}: {e}"[:200]}
            return final, steps

        select.Selector.run = run
        return self

    def __exit__(self, *exc):
        from sim2real.sysid import select

        select.Selector.run = self._orig

    def capture(self, sel, final, steps) -> None:
        self.sel, self.models = sel, list(steps) + [final]
        by_label = {c.label: c for c in sel.cands}
        missing = [lb for lb in self.labels if lb not in by_label]
        self.out = {"status": "not searched", "missing": missing} if missing else {"status": "ready"}
        self.cands = [by_label[lb] for lb in self.labels if lb in by_label]

    def judge(self, named: list[str]) -> dict:
        """The true hypothesis fitted, then judged against the answer's model (the step whose
        effects are those named)."""
        if self.out.get("status") != "ready":
            return dict(self.out)
        from sim2real.sysid.diagnose import _nrmse

        sel, cs = self.sel, self.cands
        A = next((M for M in self.models if sorted(c.label for c in M.effects) == sorted(named)), None)
        if A is None:
            return {**self.out, "status": "answer not among the steps"}
        T = self._fit_truth(A)
        sel.validate([A, T])
        tva, avt = sel.judge(A, T), sel.judge(T, A)
        cls = classify(tva, avt, sel.gain_asked(not A.effects), sel.cfg.min_t)
        held = sel.f.sh.tiles.of("heldout")
        nr = _nrmse(sel.f.sh, sel.f, [A.z, T.z], held) if len(held) else []
        return {"status": cls, "ratio": tva[0], "t_truth": tva[1], "t_answer": avt[1],
                "phi_truth": float(T.result.phi), "phi_answer": float(A.result.phi),
                "heldout_answer": float(np.mean(list(nr[0][0].values()))) if nr else float("nan"),
                "heldout_truth": float(np.mean(list(nr[1][0].values()))) if nr else float("nan"),
                "truth_params": json.dumps({n: round(float(T.z[sel.spec.index(n)]), 6)
                                            for c in cs for n in c.params})}

    def _fit_truth(self, A):
        """The true effects fitted with every nominal parameter, started at the truth's values from
        the nominal re-fit, the model file's values and the answer's fit (its parameters of the
        effects both share kept), with each effect's other parameters at every distinct point of
        its grid (a band's motor side is not in the truth's values); the lowest objective kept."""
        sel, cs = self.sel, self.cands
        N, dt = self.models[0], sel.f.sh.dt
        tails = [sorted({tuple(g[1:]) for g in c.grid}) for c in cs]
        combos = [()]
        for c, ts in zip(cs, tails):
            combos = [x + (t,) for x in combos for t in ts][:MAX_STARTS]
        best = None
        shared = {n for c in A.effects for n in c.params}
        for base in (N.z, sel.spec.default, A.z):
            for combo in combos:
                z0 = np.array(base, copy=True)
                for c, tail in zip(cs, combo):
                    start = true_start(c, self.values[c.label], dt, tail)
                    for n, v in zip(c.params, start):
                        if not (base is A.z and n in shared):
                            z0[sel.spec.index(n)] = v
                T = sel.fit(cs, z0, N.result.v0)
                if best is None or T.result.phi < best.result.phi:
                    best = T
        return best


def run_case(case: sysid_cases.Case, work: str) -> dict:
    from sim2real.sysid.candidates import label
    from sim2real.sysid.diagnose import DiagnoseConfig, diagnose

    folder = os.path.join(work, case.label)
    desc = bench.case_files(case, folder)
    # (the benchmark's keys are the candidates' labels: a global effect has no target)
    labels = sorted(bench.truth_keys(case))
    values = {lb: desc["truth_values"][lb] for lb in labels}
    t0 = time.time()
    with _Oracle(labels, values) as oracle:
        d = diagnose(DiagnoseConfig(model=os.path.join(folder, "nominal.xml"),
                                    recordings=(os.path.join(folder, "train_0.csv"),
                                                os.path.join(folder, "train_1.csv")),
                                    heldout=(os.path.join(folder, "heldout.csv"),),
                                    out=os.path.join(folder, "diagnosis"), overwrite=True, plots=False,
                                    progress=False))
    named = [label(s["effect"], s["target"]) for s in bench._selected(d) if s["effect"] != "none"]
    try:
        j = oracle.judge(named) if (set(bench.named_keys(d)) != set(labels)) else {"status": "right"}
    except Exception as e:  # noqa: BLE001  (one case's failure is its row, not the run's end)
        j = {"status": f"error: {type(e).__name__}: {e}"[:200]}
    return {"case": case.label, "kind": case.kind, "truth": " + ".join(labels) or "none",
            "named": " + ".join(named) or "none", **{k: v for k, v in j.items() if k != "missing"},
            "missing": ",".join(j.get("missing", [])), "seconds": round(time.time() - t0, 1)}


def misses(results: str) -> set[str]:
    """The cases a results folder holds as missed (``cases.csv``'s ``correct``)."""
    path = results if os.path.isabs(results) else os.path.join(bench.OUT, results)
    with open(os.path.join(path, "cases.csv")) as f:
        return {r["case"] for r in csv.DictReader(f) if r["correct"] != "True"}


def table(rows: list[dict]) -> str:
    classes = ("truth passes", "tie", "answer passes", "not searched")
    lines = ["| cases | " + " | ".join(classes) + " | other |", "|---" * (len(classes) + 2) + "|"]
    for kind, title in (("single", "single effects"), ("double", "pairs"), ("none", "parameter-only")):
        rs = [r for r in rows if r["kind"] == kind and r["status"] != "right"]
        if rs:
            counts = [sum(r["status"] == c for r in rs) for c in classes]
            lines.append(f"| {title} ({len(rs)}) | " + " | ".join(map(str, counts))
                         + f" | {len(rs) - sum(counts)} |")
    lines += ["", "| case | truth | named | class | validation ratio truth/answer | t (truth) | t (answer) "
              "| held-out NRMSE answer -> truth |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["status"] == "right":
            continue
        num = lambda k, f: (f % r[k]) if isinstance(r.get(k), float) else ""  # noqa: E731
        lines.append(f"| {r['case']} | {r['truth']} | {r['named']} | {r['status']} | {num('ratio', '%.3g')} | "
                     f"{num('t_truth', '%.2f')} | {num('t_answer', '%.2f')} | "
                     f"{num('heldout_answer', '%.4g')} -> {num('heldout_truth', '%.4g')} |")
    return "\n".join(lines) + "\n"


@dataclasses.dataclass
class Settings:
    """split: which list (as ``diagnosis_independent.py``); results: a results folder of that list
    whose missed cases are checked (a name under ``benchmarks/results/diagnosis_independent/`` or a
    path); cases: instead, a file of case labels, one per line; work: where generated cases are
    kept; out: where the table goes; tag: suffix of its name; jobs: processes; note: a line for the
    test list's log (a run on ``test`` or ``fresh`` is logged there)."""
    split: Literal[sysid_cases.SPLITS] = "tuning"
    results: str = ""
    cases: str = ""
    work: str = os.path.join("runs", "sysid_cases")
    out: str = OUT
    tag: str = ""
    jobs: int = 1
    note: str = ""


def main(args: Settings):
    if bool(args.results) == bool(args.cases):
        raise SystemExit("give results= (a results folder: its missed cases) or cases= (a file of labels), not both")
    if args.results:
        want = misses(args.results)
    else:
        with open(args.cases) as f:
            want = {ln.strip() for ln in f if ln.strip()}
    listed = sysid_cases.split_cases(args.split)
    cases = [c for c in listed if c.label in want]
    unknown = want - {c.label for c in cases}
    if unknown:
        raise SystemExit(f"not cases of the {args.split} list: {sorted(unknown)[:5]}")
    import jax

    devices = max(1, cpu_cores() // args.jobs)
    jax.config.update("jax_num_cpu_devices", devices)
    print(f"{len(cases)} cases of the {args.split} list, {args.jobs} at a time", flush=True)
    os.makedirs(args.work, exist_ok=True)
    os.makedirs(args.out, exist_ok=True)
    t_start = time.time()
    rows = []
    if args.jobs > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(args.jobs) as ex:
            for r in ex.map(run_case, cases, [args.work] * len(cases)):
                rows.append(r)
                print(_line(r), flush=True)
    else:
        for c in cases:
            rows.append(run_case(c, args.work))
            print(_line(rows[-1]), flush=True)
    base = os.path.join(args.out, args.split + args.tag)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(base + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, keys)
        w.writeheader()
        w.writerows(rows)
    text = (f"## The oracle check of the {args.split} list"
            f"{' (' + args.results + ')' if args.results else ''}: {len(rows)} cases\n\n" + table(rows))
    with open(base + ".md", "w") as f:
        f.write(text)
    print(text)
    if args.split in ("test", "fresh"):
        with open(os.path.join(bench.OUT, f"{args.split}_split_looks.md"), "a") as f:
            f.write(f"- {time.strftime('%Y-%m-%d %H:%M')}: commit {bench._commit()}, {len(rows)} cases, "
                    f"{time.time() - t_start:.0f} s. the oracle check (`diagnosis_ceiling.py`), no answer "
                    f"changed or scored. {args.note}\n")


def _line(r: dict) -> str:
    extra = (f"ratio {r['ratio']:.3g} t {r['t_truth']:.2f}/{r['t_answer']:.2f}"
             if isinstance(r.get("ratio"), float) else r.get("missing", ""))
    return f"{r['status']:14s} {r['case']:60s} named {r['named']:40s} {extra} {r['seconds']}s"


if __name__ == "__main__":
    sys.exit(main(settings(Settings, sys.argv[1:])))
