"""Diagnose why a simulator and real recordings disagree.

    python scripts/diagnose.py model=PATH.xml recordings='[a.csv,b.csv]' heldout='[c.csv]' out=DIR

With no model and no recordings it diagnoses the bundled EMPS hardware data (the demo):
nominal axis model (mass + viscous friction under the drive's PD loop), fitted on DATA_EMPS,
checked on DATA_EMPS_PULSES. Any field of ``sim2real.sysid.diagnose.DiagnoseConfig`` can be
set as key=value. Writes DIR/diagnosis.json, DIR/report.md, DIR/fitted.xml and the figures.
"""
import os
import sys

from sim2real.common import compile_cache
from sim2real.common.cli import main_guard


def main(argv):
    from sim2real.common import config as config_lib
    from sim2real.sysid import emps, report
    from sim2real.sysid.diagnose import DiagnoseConfig, diagnose

    cfg = config_lib.load(DiagnoseConfig, argv)
    demo = not cfg.model and not cfg.recordings
    if demo:  # the bundled .mat files are read directly (recordings.py knows their layout)
        cfg = config_lib.load(DiagnoseConfig, argv + [f"model={emps.NOMINAL_XML}",
                                                      f"recordings=[{emps.RECORDINGS['estimation']}]",
                                                      f"heldout=[{emps.RECORDINGS['validation']}]"])
    d = diagnose(cfg)
    print(f"answer: {d['answer']}")
    for s in d["selected"]:
        print(f"  {s['effect']}" + (f" at {s['target']}" if s["target"] else "")
              + f"  (validation error x{s['validation_ratio']:.3f}, t = {s['t']:.1f})")
        for k, v in s["params"].items():
            std = s["std"].get(k)
            print(f"    {k} = {v:.6g}" + (f" +- {std:.2g}" if std is not None and std == std else "")
                  + (f" {s['units'][k]}" if k in s.get("units", {}) else "")
                  + (" (not identified: notes)" if k in s.get("unidentified", ()) else "")
                  + (" (a bound: notes)" if k == s.get("at_bound") else ""))
    for note in d["notes"]:
        print(f"  note: {note}")
    f = d["fit"]
    print(f"held-out NRMSE ({f['metric']}): {f['before']:.4g} -> {f['after']:.4g} ({f['change']})")
    if f.get("left"):
        print(report.left_text(d).replace("**", ""))
    if demo:
        sel = next((s for s in d["selected"] if s["effect"] == "coulomb_friction"), None)
        if sel is not None:
            fc = sel["params"]["coulomb:axis"]
            asym = sel["params"].get("coulomb_asym:axis", 0.0)
            ref = emps.REFERENCE
            print(f"EMPS reference: Fc = {ref['Fc']} N (found {fc:.4g} N, {100 * abs(fc - ref['Fc']) / ref['Fc']:.1f}% off), "
                  f"offset = {ref['offset']} N (found {fc * asym:.4g} N)")
    print(f"report: {os.path.join(cfg.out, 'report.md')}  ({d['seconds']} s)")


HELP = ('sim2real.sysid.diagnose:DiagnoseConfig',)  # the typed configs whose keys ``-h`` lists


def run(argv=None):
    """Console entry point ``sim2real-diagnose`` (and ``python -m sim2real diagnose``)."""
    from sim2real.envs import parallel
    from sim2real.sysid import shooting

    try:  # sysid.shooting's physics vectors per call split over the cores (only before JAX starts)
        parallel.use_cpu_cores(min(parallel.cpu_cores(), shooting.B))
    except RuntimeError:
        pass
    compile_cache.enable()  # compiled programs kept between runs (common/compile_cache.py says why)
    main_guard(main, sys.argv[1:] if argv is None else argv, doc=__doc__, configs=HELP)


if __name__ == "__main__":
    run()
