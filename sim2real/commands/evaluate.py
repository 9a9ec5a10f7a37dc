"""Evaluate a run's policy over a grid of physics values and draw a return heat map.

    python scripts/evaluate.py run=runs/pendulum_udr x=mass:pole=0.3:2.0:9 y=gain:motor=1:3:9 episodes=4

``x`` (and optionally ``y``) are ``name=low:high:count`` or ``name=v1,v2,...``; other parameters
stay at the run's fixed values. Writes ``<run>/eval/returns.csv`` and ``returns.png`` (the
training DR box is outlined). All seeds of the run are evaluated and averaged. The latest
checkpoint is evaluated, or ``policy.msgpack`` where the folder has no ``checkpoints/``.

``adapt=true`` (ES-MAML runs) first adapts the policy to each grid cell with the run's
adaptation operator (its inner PPO updates on that cell's physics), then evaluates (few-shot
evaluation, seed 004 Fig. 1); the un-adapted returns go to ``returns_before.csv``.
``progress=false`` hides the progress bar. Every key is a field of
``sim2real.tools.evaluate.EvaluateConfig`` (``config=eval.yaml`` works as for training).
"""
import sys

from sim2real.common import compile_cache
from sim2real.common.cli import main_guard


def main(argv):
    import numpy as np

    from sim2real.common import config as config_lib
    from sim2real.tools.evaluate import EvaluateConfig, evaluate_run

    res = evaluate_run(config_lib.load(EvaluateConfig, argv))
    ret = res["returns"]
    print(f"wrote {res['out']}/returns.csv and returns.png; mean return {ret.mean():.1f}, "
          f"min {ret.min():.1f}, max {ret.max():.1f}"
          + (f" (before adaptation {np.mean(res['before']):.1f})" if res["before"] is not None else ""))


HELP = ('sim2real.tools.evaluate:EvaluateConfig',)  # the typed configs whose keys ``-h`` lists


def run(argv=None):
    """Console entry point ``sim2real-evaluate`` (and ``python -m sim2real evaluate``)."""
    compile_cache.enable()  # compiled programs kept between runs (common/compile_cache.py says why)
    main_guard(main, sys.argv[1:] if argv is None else argv, doc=__doc__, configs=HELP)


if __name__ == "__main__":
    run()
