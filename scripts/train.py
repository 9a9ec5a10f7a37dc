"""Train a policy: ``python scripts/train.py config=configs/pendulum.yaml key=value ...``.

The command lives in ``sim2real/commands/train.py`` (installed as ``sim2real-train``; also
``python -m sim2real train``); ``-h`` lists every key.
"""
from sim2real.commands.train import main, run

__all__ = ["main", "run"]  # main: tests call it in-process

if __name__ == "__main__":
    run()
