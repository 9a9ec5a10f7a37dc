"""Is the answer decided by the data or by a setting? Halve and double the two data-chosen
settings (smoothing window, prediction horizon) and see whether the named effects change.

    python benchmarks/diagnosis_stability.py                      # EMPS + 5 tuning-half cases
    python benchmarks/diagnosis_stability.py cases=[EMPS,040_belt_stage_coulomb_friction@belt]

Only tuning-half cases (even seeds) are accepted: the test half stays frozen.
"""
from __future__ import annotations

import dataclasses
import json
import os
import sys

from sim2real.common.cli import settings

import sysid_cases

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results", "diagnosis_stability")
DEFAULT_CASES = ("EMPS", "018_pendulum_geared_action_delay", "040_belt_stage_coulomb_friction@belt",
                 "034_arm2_motor_lag@m_shoulder", "024_linear_axis_joint_stiffness@axis", "092_arm2_none")


def _inputs(label: str, work: str):
    if label == "EMPS":
        from sim2real.sysid import emps

        return emps.NOMINAL_XML, (emps.RECORDINGS["estimation"],), (emps.RECORDINGS["validation"],)
    case = next(c for c in sysid_cases.build_cases() if c.label == label)
    if case.split != "tuning":
        raise SystemExit(f"{label}: a test-half case; this benchmark reads the tuning half only")
    folder = os.path.join(work, label)
    sysid_cases.generate(case, folder)
    return (os.path.join(folder, "nominal.xml"), (os.path.join(folder, "train_0.csv"), os.path.join(folder, "train_1.csv")),
            (os.path.join(folder, "heldout.csv"),))


def run(label: str, work: str) -> list[dict]:
    from sim2real.sysid.diagnose import DiagnoseConfig, diagnose

    xml, train, held = _inputs(label, work)
    base = dict(model=xml, recordings=train, heldout=held, overwrite=True, plots=False, progress=False,
                out=os.path.join(work, f"stability_{label}"))
    d0 = diagnose(DiagnoseConfig(**base))
    dt = d0["sample_period"]
    window = max(d0["smoothing_window_samples"]) * dt
    horizon = d0["horizon_samples"] * dt
    rows = []
    for name, extra in (("default", {}), ("window x0.5", {"window_seconds": 0.5 * window}),
                        ("window x2", {"window_seconds": 2 * window}), ("horizon x0.5", {"horizon_seconds": 0.5 * horizon}),
                        ("horizon x2", {"horizon_seconds": 2 * horizon})):
        d = d0 if not extra else diagnose(DiagnoseConfig(**base, **extra))
        named = sorted(f"{s['effect']}@{s['target']}" if s["target"] else s["effect"] for s in d["selected"])
        rows.append({"case": label, "setting": name, "window_s": round(window, 4), "horizon_s": round(horizon, 4),
                     "answer": d["answer"], "named": named, "after_over_before": round(d["fit"]["after"] / d["fit"]["before"], 4)})
        print(json.dumps(rows[-1]), flush=True)
    return rows


@dataclasses.dataclass
class Settings:
    """cases: case labels (``[a,b]``); work: where generated cases are kept; out: results folder."""
    cases: tuple[str, ...] = DEFAULT_CASES
    work: str = os.path.join("runs", "sysid_cases")
    out: str = OUT


def main(args: Settings):
    rows = [r for label in args.cases for r in run(label, args.work)]
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump(rows, f, indent=1)
    lines = ["| case | default: named | window ×0.5 | window ×2 | horizon ×0.5 | horizon ×2 |", "|---|---|---|---|---|---|"]
    same = 0
    for label in args.cases:
        rs = [r for r in rows if r["case"] == label]
        show = [", ".join(r["named"]) or r["answer"] for r in rs]
        same += sum(r["named"] == rs[0]["named"] for r in rs[1:])
        lines.append(f"| {label} | " + " | ".join([show[0]] + [("same" if r["named"] == rs[0]["named"] else s)
                                                              for r, s in zip(rs[1:], show[1:])]) + " |")
    lines.append(f"\nSame answer as the default in {same} of {4 * len(args.cases)} changed settings.")
    with open(os.path.join(args.out, "table.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
