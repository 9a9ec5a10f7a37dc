"""The command line: one module per command (``train``, ``evaluate``, ``diagnose``, ``record``,
``loop``, ``render``), each a ``main(argv)`` and a ``run()`` console entry point (``sim2real-<command>``, or
``python -m sim2real <command> key=value ...``). ``scripts/<command>.py`` call the same code."""
from __future__ import annotations

COMMANDS = ("train", "evaluate", "diagnose", "record", "loop", "render")
__all__ = list(COMMANDS)


def __getattr__(name):
    if name in COMMANDS:
        import importlib

        return importlib.import_module(f"sim2real.commands.{name}")
    raise AttributeError(f"module 'sim2real.commands' has no attribute '{name}'")
