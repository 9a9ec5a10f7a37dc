"""Parameter kinds as plug-ins: every module here defines :class:`Kind` subclasses, found on import.

Adding a kind (a new unmodelled effect, say) is one module here plus its test: it declares its
parameters, what they change in the model or the dynamics, how the diagnosis searches for it
and how a fitted value is written into MJCF (``base.py`` lists the hooks). ``drag.py`` is the
example: quadratic drag, added this way.
"""
from __future__ import annotations

import importlib
import pkgutil

from sim2real.physics.kinds.base import ACTUATOR, BODY, JOINT, Kind

_REGISTRY: list[Kind] | None = None
_OWNERS: dict[str, Kind] = {}


def all_kinds() -> list[Kind]:
    """One instance of every plug-in, in ``order``."""
    global _REGISTRY
    if _REGISTRY is None:
        for mod in pkgutil.iter_modules(__path__):
            if mod.name != "base":
                importlib.import_module(f"{__name__}.{mod.name}")
        found, seen = [], set()
        stack = list(Kind.__subclasses__())
        while stack:
            k = stack.pop()
            stack.extend(k.__subclasses__())
            if k.owns and k not in seen:
                seen.add(k)
                found.append(k())
        for k in found:
            for kind in k.owns:
                if kind in _OWNERS:
                    raise RuntimeError(f"parameter kind '{kind}' is owned twice "
                                       f"({type(_OWNERS[kind]).__name__}, {type(k).__name__})")
                _OWNERS[kind] = k
        _REGISTRY = sorted(found, key=lambda k: (k.order, type(k).__name__))
    return _REGISTRY


def owner(kind: str) -> Kind | None:
    """The plug-in that owns ``Param.kind`` ``kind`` (None: a kind no plug-in gives meaning to)."""
    all_kinds()
    return _OWNERS.get(kind)


def attached(attach: str) -> list[Kind]:
    """Plug-ins declaring an effect parameter on every ``attach`` object, in declaration order."""
    return [k for k in all_kinds() if k.attach == attach and k.declares]


def offering(attach: str, default_only: bool = False) -> list[Kind]:
    """Plug-ins offering a diagnosis hypothesis for ``attach`` objects (``""``: global), in library order."""
    ks = [k for k in all_kinds() if k.effect and k.attach == attach and (k.default_candidate or not default_only)]
    return sorted(ks, key=lambda k: k.order if k.candidate_order is None else k.candidate_order)


__all__ = ["ACTUATOR", "BODY", "JOINT", "Kind", "all_kinds", "attached", "offering", "owner"]
