"""Train a policy: ``python scripts/train.py config=configs/pendulum.yaml key=value ...``.

Any field of ``sim2real.training.driver.TrainConfig`` (dotted for nested sections, e.g. ``ppo.lr=1e-3``)
can be overridden. ``resume=true`` continues the run folder's latest checkpoint.
"""
import sys

from sim2real.common import compile_cache
from sim2real.common.cli import main_guard


def main(argv):
    from sim2real.training.runs import summary
    from sim2real.training.driver import config_from_args, train

    cfg = config_from_args(argv)
    out = train(cfg)
    if out["metrics"] is None:
        print(f"run folder: {out['run_dir']}: finished already (raise total_steps= to train on)")
        return
    keys = ("episode_return", "episode_length", "entropy", "fitness_mean", "fitness_max")
    last = {k: round(v, 4) for k, v in summary(out["metrics"]).items() if k in keys}
    print(f"run folder: {out['run_dir']}  last chunk: {last}")


HELP = ('sim2real.training.runs:TrainConfig',)  # the typed configs whose keys ``-h`` lists


def run(argv=None):
    """Console entry point ``sim2real-train`` (and ``python -m sim2real train``)."""
    compile_cache.enable()  # compiled programs kept between runs (common/compile_cache.py says why)
    main_guard(main, sys.argv[1:] if argv is None else argv, doc=__doc__, configs=HELP)


if __name__ == "__main__":
    run()
