"""Curated package exports loaded on first use (PEP 562), so importing a package stays cheap and
free of side effects, and a heavy or optional dependency is imported only by who uses it."""
from __future__ import annotations

import importlib
import sys


def exports(package: str, table: dict[str, str]):
    """``(__getattr__, __dir__, __all__)`` for ``package`` exporting ``name -> "module:attribute"``."""
    names = sorted(table)

    def __getattr__(name: str):
        if name not in table:
            raise AttributeError(f"module '{package}' has no attribute '{name}'")
        module, attr = table[name].split(":")
        value = getattr(importlib.import_module(module), attr)
        setattr(sys.modules[package], name, value)  # cached: looked up once
        return value

    def __dir__():
        return names

    return __getattr__, __dir__, names
