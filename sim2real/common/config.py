"""Typed configs from YAML plus ``key=value`` overrides, with errors that name the bad key.

    python scripts/train.py config=configs/pendulum_udr.yaml ppo.lr=1e-3 ppo.net.hidden=[128,128]

Values are parsed as YAML (``true``, ``1e-3``, ``[1, 2]``) except for text fields, which keep the
text as written (``tag=0.10`` stays ``'0.10'``); dotted keys reach nested dataclasses; an unknown key
is an error that lists the nearest valid keys; a ``Literal`` field names its choices; a field
without a default must be given. Every script and benchmark reads its settings this way.
"""
from __future__ import annotations

import dataclasses
import difflib
import os
import types
import typing
from typing import Any

import yaml


class ConfigError(ValueError):
    """A config file or override that does not fit the typed config."""


def _hints(cls) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def all_keys(cls, prefix: str = "") -> list[str]:
    """Every dotted key of a dataclass config (nested ones included)."""
    keys = []
    for f in dataclasses.fields(cls):
        t = _hints(cls)[f.name]
        keys.append(prefix + f.name)
        if dataclasses.is_dataclass(t):
            keys += all_keys(t, prefix + f.name + ".")
    return keys


def _attribute_docs(cls) -> dict[str, str]:
    """``{field: first sentence}`` from the ``Attributes:`` section of ``cls``'s docstring."""
    import inspect
    import re

    docs, name, indent = {}, None, None
    lines = inspect.cleandoc(cls.__doc__ or "").splitlines()
    if "Attributes:" not in lines:
        return docs
    for line in lines[lines.index("Attributes:") + 1:]:
        if not line.strip():
            continue
        width = len(line) - len(line.lstrip())
        m = re.match(r"\s*([\w, ]+):\s*(.*)", line)
        if m and (indent is None or width == indent):
            indent = width
            names = [n.strip() for n in m.group(1).split(",")]
            for n in names:
                docs[n] = m.group(2)
            name = names
        elif name and indent is not None and width > indent:
            for n in name:
                docs[n] += " " + line.strip()
        else:
            break
    return {n: _first_clause(text) for n, text in docs.items()}


def _first_clause(text: str, width: int = 110) -> str:
    """Up to the first '. ' or '; ' outside parentheses (not after "e.g" / "i.e"), at most ``width``."""
    depth = 0
    for i, c in enumerate(text):
        depth += (c == "(") - (c == ")")
        if depth == 0 and c in ".;" and text[i + 1:i + 2] in (" ", "") and not text[:i].endswith(("e.g", "i.e")):
            text = text[:i]
            break
    return text if len(text) <= width else text[:width - 3] + "..."


def describe(cls, prefix: str = "") -> list[tuple[str, str, str, str]]:
    """``(dotted key, type, default, one line of doc)`` for every key of a dataclass config, nested
    sections included (what ``-h`` prints)."""
    rows, hints, docs = [], _hints(cls), _attribute_docs(cls)
    for f in dataclasses.fields(cls):
        t = hints[f.name]
        if dataclasses.is_dataclass(t):
            rows += describe(t, prefix + f.name + ".")
            continue
        if f.default is not dataclasses.MISSING:
            default = repr(f.default)
        elif f.default_factory is not dataclasses.MISSING:
            default = repr(f.default_factory())
        else:
            default = "(required)"
        kind = f.type if isinstance(f.type, str) else getattr(t, "__name__", str(t))
        if typing.get_origin(t) is typing.Literal:  # its choices, also where an expression names them
            kind = "Literal[" + ", ".join(map(repr, typing.get_args(t))) + "]"
        default = default if len(default) <= 30 else default[:27] + "..."
        rows.append((prefix + f.name, kind.replace("typing.", ""), default, docs.get(f.name, "")))
    return rows


def help_text(cls) -> str:
    """Every key of ``cls`` as aligned lines: ``key  type  default  doc``."""
    rows = describe(cls)
    w = [max(len(r[i]) for r in rows) for i in range(3)]
    return "\n".join(f"  {k:<{w[0]}}  {t:<{w[1]}}  {d:<{w[2]}}  {doc}".rstrip() for k, t, d, doc in rows)


def _unknown(key: str, cls, prefix: str) -> ConfigError:
    valid = all_keys(cls, prefix)
    close = difflib.get_close_matches(prefix + key, valid, n=3, cutoff=0.5)
    hint = f" Did you mean: {', '.join(close)}?" if close else ""
    return ConfigError(f"unknown config key '{prefix}{key}'.{hint} Valid keys: {', '.join(valid)}")


def _coerce(value, t, where: str):
    origin = typing.get_origin(t)
    args = typing.get_args(t)
    if t is Any:
        return value
    if origin is typing.Literal:
        if value not in args:
            raise ConfigError(f"{where}: {value!r} is not one of {', '.join(map(str, args))}")
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        for a in args:
            if a is type(None):
                continue
            try:
                return _coerce(value, a, where)
            except ConfigError:
                pass
        raise ConfigError(f"{where}: {value!r} does not fit {t}")
    if dataclasses.is_dataclass(t):
        if isinstance(value, t):
            return value
        if not isinstance(value, dict):
            raise ConfigError(f"{where}: expected a mapping of {t.__name__} fields, got {value!r}")
        return from_dict(t, value, where + ".")
    if origin in (tuple, list):
        if isinstance(value, str) or not isinstance(value, (list, tuple)):
            value = [value]
        if origin is tuple and len(args) == 2 and args[1] is Ellipsis:
            return tuple(_coerce(v, args[0], f"{where}[{i}]") for i, v in enumerate(value))
        if origin is tuple and args:
            if len(args) != len(value):
                raise ConfigError(f"{where}: expected {len(args)} values, got {value!r}")
            return tuple(_coerce(v, a, f"{where}[{i}]") for i, (v, a) in enumerate(zip(args, value)))
        return list(value)
    if origin is dict:
        if not isinstance(value, dict):
            raise ConfigError(f"{where}: expected a mapping, got {value!r}")
        return dict(value)
    if t is bool:
        if isinstance(value, bool):
            return value
        raise ConfigError(f"{where}: expected true/false, got {value!r}")
    if t is int:
        if isinstance(value, str):  # YAML 1.1 reads "1e5" (no dot) as a string
            try:
                value = float(value.replace("_", ""))
            except ValueError:
                pass
        if isinstance(value, bool) or not (isinstance(value, int) or (isinstance(value, float) and value.is_integer())):
            raise ConfigError(f"{where}: expected an integer, got {value!r}")
        return int(value)
    if t is float:
        if isinstance(value, str):  # YAML 1.1 reads "3e-4" (no dot) as a string
            try:
                value = float(value)
            except ValueError:
                pass
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{where}: expected a number, got {value!r}")
        return float(value)
    if t is str:
        if not isinstance(value, str):
            raise ConfigError(f"{where}: expected a string, got {value!r}")
        return value
    return value


def from_dict(cls, d: dict, prefix: str = ""):
    """Build dataclass ``cls`` from a (nested) dict, checking keys and types."""
    hints = _hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    kwargs = {}
    for k, v in (d or {}).items():
        if k not in names:
            raise _unknown(k, cls, prefix)
        kwargs[k] = _coerce(v, hints[k], prefix + k)
    missing = [prefix + f.name for f in dataclasses.fields(cls) if f.name not in kwargs
               and f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
    if missing:
        raise ConfigError(f"missing required key{'s' * (len(missing) > 1)} {', '.join(missing)}")
    return cls(**kwargs)


def to_dict(cfg) -> dict:
    def conv(x):
        if dataclasses.is_dataclass(x):
            return {f.name: conv(getattr(x, f.name)) for f in dataclasses.fields(x)}
        if isinstance(x, (tuple, list)):
            return [conv(v) for v in x]
        if isinstance(x, dict):
            return {k: conv(v) for k, v in x.items()}
        return x

    return conv(cfg)


def _is_text(t) -> bool:
    """A ``str`` (or ``str | None``) field: its override is kept as written (``out=2024``, ``tag=0.10``)."""
    if typing.get_origin(t) in (typing.Union, types.UnionType):
        return set(typing.get_args(t)) == {str, type(None)}
    return t is str


def _parse(text: str, t):
    if _is_text(t) and not (text in ("null", "~") and t is not str):
        return text
    return yaml.safe_load(text) if text != "" else ""


def _set(d: dict, dotted: str, text: str, cls):
    """Put the override ``dotted=text`` into the nested dict ``d``, its text parsed for the field's type."""
    parts = dotted.split(".")
    cur_cls, cur = cls, d
    for i, p in enumerate(parts):
        names = {f.name for f in dataclasses.fields(cur_cls)}
        if p not in names:
            raise _unknown(p, cur_cls, ".".join(parts[:i]) + ("." if i else ""))
        if i == len(parts) - 1:
            cur[p] = _parse(text, _hints(cur_cls)[p])
            return
        t = _hints(cur_cls)[p]
        if typing.get_origin(t) is dict:  # free-form section (checked later by its owner)
            cur = cur.setdefault(p, {})
            for q in parts[i + 1:-1]:
                cur = cur.setdefault(q, {})
            cur[parts[-1]] = _parse(text, Any)
            return
        if not dataclasses.is_dataclass(t):
            raise ConfigError(f"'{'.'.join(parts[:i + 1])}' is not a section; cannot set '{dotted}'")
        cur = cur.setdefault(p, {})
        if dataclasses.is_dataclass(cur):
            cur = to_dict(cur)
        cur_cls = t


def _merge(base: dict, extra: dict) -> dict:
    out = dict(base)
    for k, v in extra.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def parse_args(argv: list[str], raw: bool = False) -> tuple[str | None, dict[str, Any]]:
    """``['config=a.yaml', 'ppo.lr=1e-3']`` -> ``('a.yaml', {'ppo.lr': 0.001})`` (values read as YAML;
    with ``raw`` the texts as written, for ``load`` to read by each field's type)."""
    path, overrides = None, {}
    for a in argv:
        if "=" not in a:
            raise ConfigError(f"argument '{a}' is not of the form key=value")
        k, v = a.split("=", 1)
        k = k.strip().lstrip("-")
        if k == "config":
            path = v
        else:
            overrides[k] = v if raw else _parse(v, Any)
    return path, overrides


def split(argv: list[str], cls) -> tuple[list[str], list[str]]:
    """``argv`` parted into the ``key=value``s of ``cls``'s fields and the rest (another config's),
    for a script that takes its own settings and, say, a ``TrainConfig``'s."""
    names = {f.name for f in dataclasses.fields(cls)}
    mine = [a for a in argv if a.split("=", 1)[0].strip().lstrip("-").split(".")[0] in names]
    return mine, [a for a in argv if a not in mine]


BUNDLED = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "configs")


def bundled(name: str) -> str:
    """``config=NAME``: a file where one exists, else the bundled ``sim2real/configs/NAME.yaml``
    (installed with the package, so ``sim2real-train config=pendulum`` works from any folder)."""
    if os.path.exists(name) or os.sep in name or name.endswith((".yaml", ".yml")):
        return name
    path = os.path.join(BUNDLED, name + ".yaml")
    if not os.path.exists(path):
        known = sorted(f[:-5] for f in os.listdir(BUNDLED) if f.endswith(".yaml"))
        raise ConfigError(f"config={name}: no such file, nor a bundled config (bundled: {', '.join(known)})")
    return path


def load(cls, argv: list[str]):
    """Config of type ``cls`` from ``config=PATH`` (YAML; or a bundled config's name) and
    ``key=value`` overrides."""
    path, overrides = parse_args(argv, raw=True)
    data: dict = {}
    if path:
        path = bundled(path)
        try:
            with open(path) as f:
                data = yaml.safe_load(f) or {}
        except FileNotFoundError:
            raise ConfigError(f"config file '{path}' not found") from None
        except yaml.YAMLError as e:
            raise ConfigError(f"config file '{path}' is not valid YAML: {e}") from None
        if not isinstance(data, dict):
            raise ConfigError(f"config file '{path}' must hold a mapping at the top level")
    nested: dict = {}
    for k, v in overrides.items():
        _set(nested, k, v, cls)
    return from_dict(cls, _merge(data, nested))


def save(cfg, path: str) -> None:
    with open(path, "w") as f:
        yaml.safe_dump(to_dict(cfg), f, sort_keys=False)
