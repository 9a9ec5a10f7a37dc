"""Evaluate a run's policy over a grid of physics values and draw a return heat map.

The command lives in ``sim2real/commands/evaluate.py`` (installed as ``sim2real-evaluate``; also
``python -m sim2real evaluate``); ``-h`` lists every key.
"""
from sim2real.commands.evaluate import main, run

__all__ = ["main", "run"]  # main: tests call it in-process

if __name__ == "__main__":
    run()
