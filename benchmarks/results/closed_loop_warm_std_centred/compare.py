"""The loop on the centred box against the columns run earlier on the same chains (the same
nominal policies to the digit, reused with ``closed_loop.py nominal=``): prints and writes
``summary.md`` with ``closed_loop.paired_lines``. The span box's loops are renamed ``span_1`` and
``span_2`` so that they count as other methods.

    python benchmarks/results/closed_loop_warm_std_centred/compare.py
"""
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
RES = os.path.dirname(HERE)
sys.path.insert(0, os.path.dirname(RES))

from closed_loop import paired_lines, read_results  # noqa: E402

# this folder's run -> (earlier results.csv, the methods taken from it, renamed where a loop)
SETS = {
    "pendulum": [("closed_loop_warm_std_span/pendulum_2core", {"nominal": "nominal", "diag_dr_1": "span_1",
                                                               "diag_dr_2": "span_2"}),
                 ("closed_loop_warm_std/pendulum", {"oracle_ft": "oracle_ft", "udr_blind_ft": "udr_blind_ft"}),
                 ("closed_loop_blind/pendulum", {"simopt": "simopt"})],
    "cartpole": [("closed_loop_warm_std_span/cartpole", {"nominal": "nominal", "diag_dr_1": "span_1",
                                                         "diag_dr_2": "span_2", "udr_blind_ft": "udr_blind_ft"}),
                 ("closed_loop_warm_std/cartpole", {"oracle_ft": "oracle_ft"}),
                 ("closed_loop_blind/cartpole", {"simopt": "simopt"})],
    "pendulum_seed1": [],  # (every column run in that call: nominal, oracle_ft, udr_blind_ft, simopt)
    "cartpole_seed1": [("closed_loop_warm_std_span/cartpole_seed1", {"nominal": "nominal", "diag_dr_1": "span_1",
                                                                     "diag_dr_2": "span_2",
                                                                     "udr_blind_ft": "udr_blind_ft",
                                                                     "simopt": "simopt"})],
}


def rows_of(path, rename=None):
    return [dict(r, method=rename[r["method"]]) if rename else r for r in read_results(path)
            if rename is None or r["method"] in rename]


def section(title, rows, spread):
    """A summary section: each method's mean (with min and max where ``spread``), then the loop
    against every other method paired by seed."""
    means = {}
    for r in rows:
        means.setdefault(r["method"], []).append(float(r["return"]))
    head = "| method | mean [min, max] |" if spread else "| method | mean |"
    return ([f"## {title}", "", head, "|---|---|"]
            + [f"| {m} | {np.mean(v):.1f}" + (f" [{min(v):.1f}, {max(v):.1f}]" if spread else "") + " |"
               for m, v in means.items()]
            + paired_lines(rows) + [""])


def rows_by_set() -> dict[str, list[dict]]:
    """Each set of five chains (``SETS``' names) -> its rows: this folder's loop and the earlier
    columns on the same chains."""
    by_set = {}
    for name, earlier in SETS.items():
        run = os.path.join(HERE, name, name.split("_")[0])
        if os.path.exists(os.path.join(run, "results.csv")):
            by_set[name] = rows_of(run) + [r for path, ren in earlier for r in rows_of(os.path.join(RES, path), ren)]
    return by_set


def ten_chains(by_set: dict[str, list[dict]], env: str, common: bool = True) -> list[dict]:
    """Both sets of five chains of ``env`` as one list, a chain numbered 100 * set + seed for the
    pairing; ``common``: only the methods both sets have."""
    sets = [n for n in SETS if n.split("_")[0] == env]
    if not all(n in by_set for n in sets):
        return []
    keep = set.intersection(*({r["method"] for r in by_set[n]} for n in sets)) if common else None
    return [dict(r, seed=100 * k + int(r["seed"])) for k, n in enumerate(sets) for r in by_set[n]
            if keep is None or r["method"] in keep]


def main():
    lines, by_set = [], rows_by_set()
    for name, rows in by_set.items():
        lines += section(name, rows, spread=True)
    for env in ("pendulum", "cartpole"):  # both sets of five chains, the methods both have
        rows = ten_chains(by_set, env)
        if rows:
            lines += section(f"{env}, both sets of five chains (ten)", rows, spread=False)
    text = "\n".join(lines)
    print(text)
    with open(os.path.join(HERE, "summary.md"), "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()
