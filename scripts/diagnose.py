"""Diagnose why a simulator and real recordings disagree.

The command lives in ``sim2real/commands/diagnose.py`` (installed as ``sim2real-diagnose``; also
``python -m sim2real diagnose``); ``-h`` lists every key.
"""
from sim2real.commands.diagnose import main, run

__all__ = ["main", "run"]  # main: tests call it in-process

if __name__ == "__main__":
    run()
