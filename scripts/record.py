"""Roll a trained policy on a target and write recordings the diagnosis (and SimOpt) can read.

    python scripts/record.py run=runs/pendulum target=benchmarks/plants/pendulum_real.xml episodes=3 out=DIR

``target``: an MJCF file, stepped by native MuJoCo (a "real" plant in a sim-to-sim study, or a
diagnosis' ``fitted.xml``), logged at every physics step; ``name=value,...``: the run's env with
those physics values (MJX), logged per control step; empty: the run's own physics.
``run_seed``: which of the run's seeds acts; ``seed``: initial states and noise; ``noise``: std of
the position sensor's noise on an MJCF target (m or rad); ``deterministic=false`` samples actions
(more excitation for identification). Writes ``DIR/episode_000.csv``... and ``DIR/record.json``
(what was rolled, the returns).
"""
import os
import sys

from sim2real.cli import main_guard


def main(argv):
    from sim2real import config as config_lib
    from sim2real import output
    from sim2real.progress import Bar
    from sim2real.record import from_run, save

    a = config_lib.script_args(argv, {"run": "", "target": "", "episodes": 3, "out": "", "seed": 0, "run_seed": 0,
                                      "noise": 0.0, "deterministic": True, "overwrite": False, "progress": True})
    if not a["run"] or not a["out"]:
        raise config_lib.ConfigError("record needs run=RUN_DIR and out=DIR (target=PATH.xml or name=value,...)")
    if not os.path.exists(os.path.join(a["run"], "config.yaml")):
        raise FileNotFoundError(f"run={a['run']}: not a run folder (no config.yaml)")
    if a["episodes"] < 1:
        raise config_lib.ConfigError(f"episodes={a['episodes']}: must be a positive integer")
    if not a["noise"] >= 0:
        raise config_lib.ConfigError(f"noise={a['noise']}: must be >= 0 (a standard deviation)")
    inputs = [os.path.join(a["run"], "config.yaml")] + ([a["target"]] if a["target"].endswith(".xml") else [])
    output.check(a["out"], "recordings", inputs=inputs, overwrite=a["overwrite"])
    bars = []

    def advance(k, n):  # control steps of the native rollout (an MJX rollout is one jitted call)
        if not bars:
            bars.append(Bar(a["progress"], n, f"{a['episodes']} episodes on {a['target']}"))
        bars[0].step()

    try:
        rolls, what = from_run(a["run"], a["target"], a["episodes"], a["seed"], a["run_seed"], a["noise"],
                               a["deterministic"], progress=advance)
    finally:
        for b in bars:
            b.close()
    save(rolls, what, a["out"], inputs, a["overwrite"])
    print(f"wrote {a['episodes']} recordings to {a['out']} ({1 / rolls.dt:g} Hz); returns: "
          + ", ".join(f"{r:.1f}" for r in rolls.ret) + f" (mean {what['mean_return']:.1f})")


if __name__ == "__main__":
    main_guard(main, sys.argv[1:])
