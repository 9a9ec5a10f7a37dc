"""SimOpt: ``python scripts/simopt.py config=configs/simopt_pendulum.yaml key=value ...``.

Any field of ``sim2real.simopt_run.SimOptRunConfig`` can be overridden (``simopt.num_samples=1024``,
``target='{sensor_offset:hinge: 0.5}'``). ``real=recordings recordings='[a.csv,b.csv]'`` adapts the
distribution from recordings of the current policy instead of a target env (one iteration per call;
``resume=true`` for the next). Writes iterations.csv, distribution.npz, plots and policy.msgpack.
"""
import sys

from sim2real.cli import main_guard


def main(argv):
    from sim2real import config as config_lib
    from sim2real.simopt_run import SimOptRunConfig, run

    cfg = config_lib.load(SimOptRunConfig, argv)
    out = run(cfg)
    last = out["rows"][-1] if out["rows"] else {}
    show = {k: round(v, 4) for k, v in last.items() if k.startswith(("mean:", "std:")) or k == "eval_return"}
    print(f"run folder: {out['run_dir']}  last iteration: {show}")


if __name__ == "__main__":
    main_guard(main, sys.argv[1:])
