"""Roll a trained policy on a target and write recordings the diagnosis (and SimOpt) can read.

    python scripts/record.py run=runs/pendulum target=benchmarks/plants/pendulum_real.xml episodes=3 out=DIR

``target``: an MJCF file, stepped by native MuJoCo (a "real" plant in a sim-to-sim study, or a
diagnosis' ``fitted.xml``), logged at every physics step; ``name=value,...``: the run's env with
those physics values (MJX), logged per control step; empty: the run's own physics.
``run_seed``: which of the run's seeds acts; ``seed``: initial states and noise; ``noise``: std of
the position sensor's noise on an MJCF target (m or rad); ``deterministic=false`` samples actions
(more excitation for identification); ``until_end=true`` logs an episode the env would end (a
fall) on to its full length. Writes ``DIR/episode_000.csv``... and ``DIR/record.json``
(what was rolled, the returns).
"""
import os
import sys

from sim2real.common import compile_cache
from sim2real.common.cli import main_guard


def main(argv):
    from sim2real.common import config as config_lib, output
    from sim2real.common.progress import Bar
    from sim2real.tools.record import RecordConfig, from_run, save

    a = config_lib.load(RecordConfig, argv)
    if not os.path.exists(os.path.join(a.run, "config.yaml")):
        raise FileNotFoundError(f"run={a.run}: not a run folder (no config.yaml)")
    inputs = [os.path.join(a.run, "config.yaml")] + ([a.target] if a.target.endswith(".xml") else [])
    output.check(a.out, "recordings", inputs=inputs, overwrite=a.overwrite)
    bars = []

    def advance(k, n):  # control steps of the native rollout (an MJX rollout is one jitted call)
        if not bars:
            bars.append(Bar(a.progress, n, f"{a.episodes} episodes on {a.target}"))
        bars[0].step()

    try:
        rolls, what = from_run(a.run, a.target, a.episodes, a.seed, a.run_seed, a.noise,
                               a.deterministic, progress=advance, until_end=a.until_end)
    finally:
        for b in bars:
            b.close()
    save(rolls, what, a.out, inputs, a.overwrite)
    print(f"wrote {a.episodes} recordings to {a.out} ({1 / rolls.dt:g} Hz); returns: "
          + ", ".join(f"{r:.1f}" for r in rolls.ret) + f" (mean {what['mean_return']:.1f})")


HELP = ('sim2real.tools.record:RecordConfig',)  # the typed configs whose keys ``-h`` lists


def run(argv=None):
    """Console entry point ``sim2real-record`` (and ``python -m sim2real record``)."""
    compile_cache.enable()  # compiled programs kept between runs (common/compile_cache.py says why)
    main_guard(main, sys.argv[1:] if argv is None else argv, doc=__doc__, configs=HELP)


if __name__ == "__main__":
    run()
