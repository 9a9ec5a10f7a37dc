"""The sim-to-real loop, end to end: train, record on the target, diagnose, retrain; repeat.

The command lives in ``sim2real/commands/loop.py`` (installed as ``sim2real-loop``; also
``python -m sim2real loop``); ``-h`` lists every key.
"""
from sim2real.commands.loop import main, run

__all__ = ["main", "run"]  # main: tests call it in-process

if __name__ == "__main__":
    run()
