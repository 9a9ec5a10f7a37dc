"""Train a policy: ``python scripts/train.py config=configs/pendulum.yaml key=value ...``.

Any field of ``sim2real.train.TrainConfig`` (dotted for nested sections, e.g. ``ppo.lr=1e-3``)
can be overridden. ``resume=true`` continues the run folder's latest checkpoint.
"""
import sys

from sim2real.cli import main_guard


def main(argv):
    from sim2real import config as config_lib
    from sim2real.train import TrainConfig, summary, train

    cfg = config_lib.load(TrainConfig, argv)
    out = train(cfg)
    last = {k: v for k, v in summary(out["metrics"]).items() if k in ("episode_return", "episode_length", "entropy", "fitness_mean", "fitness_max")}
    print(f"run folder: {out['run_dir']}  last update: {last}")


if __name__ == "__main__":
    main_guard(main, sys.argv[1:])
