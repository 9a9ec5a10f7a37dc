"""Roll a trained policy on a target and write recordings the diagnosis (and SimOpt) can read.

The command lives in ``sim2real/commands/record.py`` (installed as ``sim2real-record``; also
``python -m sim2real record``); ``-h`` lists every key.
"""
from sim2real.commands.record import main, run

__all__ = ["main", "run"]  # main: tests call it in-process

if __name__ == "__main__":
    run()
