"""Videos of a trained policy under several physics, side by side.

The command lives in ``sim2real/commands/render.py`` (installed as ``sim2real-render``; also
``python -m sim2real render``); ``-h`` lists every key.
"""
from sim2real.commands.render import main, run

__all__ = ["main", "run"]  # main: tests call it in-process

if __name__ == "__main__":
    run()
