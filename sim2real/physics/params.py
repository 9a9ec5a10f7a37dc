"""Named physics parameters: a spec of entries with defaults and physical bounds.

A physics vector ``z`` is a flat float array ``[P]`` whose entries follow the order of a
:class:`ParamSpec`. Distributions, outer loops and context-conditioned policies all work on
such vectors (or on a sub-vector selected with :meth:`ParamSpec.subspace`).

Bounds rule (documented in the README):

* At API boundaries (config files, command line, :meth:`ParamSpec.vector`, :meth:`ParamSpec.validate`)
  a value outside ``[low, high]`` is **rejected** with an error naming the parameter, the value
  and the bounds.
* Inside ``jit`` (where nothing can raise) :func:`clip` **clips** every entry to its bounds before
  the physics sees it. A DR distribution whose support reaches past the bounds (the LSDR paper's
  Table I ranges include negative damping) therefore simulates the bound, never the impossible value.
  An env made with ``out_of_bounds="terminate"`` instead ends such an episode at its first step
  (``Env.spec_valid``), so a learned distribution can see that the value is impossible.
"""
from __future__ import annotations

import dataclasses
import difflib
from typing import Iterable, Mapping, Sequence

import jax.numpy as jnp
import numpy as np


@dataclasses.dataclass(frozen=True)
class Param:
    """One named physics parameter.

    Attributes:
      name: unique name, ``kind:target`` for per-element entries (``coulomb:thigh_joint``).
      default: nominal value (the compiled model's value, or the neutral value of an effect).
      low, high: physical bounds, inclusive.
      unit: SI unit, for reports.
      doc: one line saying what it changes.
      kind: application rule used by :mod:`sim2real.physics.model_apply` / :mod:`effects`.
      index: model index the rule acts on (body, geom, dof, actuator id), ``-1`` if global.
    """

    name: str
    default: float
    low: float
    high: float
    unit: str
    doc: str
    kind: str
    index: int = -1

    def __post_init__(self):
        if not (self.low <= self.default <= self.high):
            raise ValueError(
                f"parameter '{self.name}': default {self.default} outside its bounds "
                f"[{self.low}, {self.high}]"
            )


class UnknownNameError(KeyError, ValueError):
    """An unknown parameter / env / column name; the message lists what exists."""

    def __str__(self) -> str:  # KeyError quotes its message; keep it readable
        return str(self.args[0])


def unknown_name_message(what: str, name: str, known: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, list(known), n=3)
    hint = f" Did you mean {', '.join(repr(c) for c in close)}?" if close else ""
    return f"unknown {what} '{name}'.{hint} Known: {', '.join(known)}"


class ParamSpec:
    """Ordered collection of :class:`Param`; static (hashable by identity), never traced."""

    def __init__(self, params: Iterable[Param]):
        self.params: tuple[Param, ...] = tuple(params)
        names = [p.name for p in self.params]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"duplicate parameter names: {sorted(dup)}")
        self.names: tuple[str, ...] = tuple(names)
        self._index = {n: i for i, n in enumerate(names)}
        self.default = np.array([p.default for p in self.params], np.float32)
        self.low = np.array([p.low for p in self.params], np.float32)
        self.high = np.array([p.high for p in self.params], np.float32)

    def __len__(self) -> int:
        return len(self.params)

    def __str__(self) -> str:
        """A table: name, default, bounds, unit and what each parameter changes."""
        w = max((len(n) for n in self.names), default=4)
        rows = [f"{'name':{w}s}  {'default':>10s}  {'low':>10s}  {'high':>10s}  unit    what"]
        rows += [f"{p.name:{w}s}  {p.default:10.4g}  {p.low:10.4g}  {p.high:10.4g}  {p.unit:6s}  {p.doc}"
                 for p in self.params]
        return "\n".join(rows)

    def __contains__(self, name: str) -> bool:
        return name in self._index

    def __getitem__(self, name: str) -> Param:
        return self.params[self.index(name)]

    def index(self, name: str) -> int:
        if name not in self._index:
            raise UnknownNameError(unknown_name_message("physics parameter", name, self.names))
        return self._index[name]

    def indices(self, names: Sequence[str]) -> np.ndarray:
        return np.array([self.index(n) for n in names], np.int32)

    def of_kind(self, kind: str) -> list[tuple[int, Param]]:
        return [(i, p) for i, p in enumerate(self.params) if p.kind == kind]

    # ---- API-boundary helpers (raise on bad input) -------------------------------------
    def check_value(self, name: str, value: float) -> float:
        p = self[name]
        value = float(value)
        if not np.isfinite(value):
            raise ValueError(f"physics parameter '{name}' = {value} is not finite")
        if not (p.low <= value <= p.high):
            raise ValueError(f"physics parameter '{name}' = {value} is outside its physical bounds {bounds_text(p)}")
        return value

    def vector(self, values: Mapping[str, float] | None = None) -> np.ndarray:
        """Full ``[P]`` vector: defaults, with ``values`` (validated) substituted."""
        z = self.default.copy()
        for name, v in (values or {}).items():
            z[self.index(name)] = self.check_value(name, v)
        return z

    def validate(self, z, where: str = "z") -> np.ndarray:
        """Check shape ``[..., P]``, finiteness and bounds of a concrete vector; returns it."""
        z = np.asarray(z, np.float32)
        if z.ndim == 0 or z.shape[-1] != len(self):
            raise ValueError(
                f"{where} has shape {z.shape}; expected [..., {len(self)}] "
                f"(parameters: {', '.join(self.names)})"
            )
        bad = ~np.isfinite(z) | (z < self.low) | (z > self.high)
        if bad.any():
            i = int(np.argwhere(bad)[0][-1])
            v = z[..., i].ravel()[np.argmax(bad[..., i].ravel())]
            p = self.params[i]
            raise ValueError(f"{where}: parameter '{p.name}' = {v} is outside its physical bounds {bounds_text(p)}")
        return z

    def describe(self) -> str:
        rows = [f"{p.name:32s} {p.default:>10.4g}  [{p.low:.4g}, {p.high:.4g}] {p.unit:8s} {p.doc}"
                for p in self.params]
        return "\n".join(rows)


def bounds_text(p: Param) -> str:
    """``p``'s bounds as the errors state them (with why, where they allow one value only)."""
    return f"[{p.low:g}, {p.high:g}] {p.unit}" + (f" ({p.doc})" if p.low == p.high else "")


def clip(spec: ParamSpec, z: jnp.ndarray) -> jnp.ndarray:
    """Clip ``z [..., P]`` to the physical bounds (the in-jit half of the bounds rule)."""
    return jnp.clip(z, spec.low, spec.high)


def in_bounds(spec: ParamSpec, z: jnp.ndarray) -> jnp.ndarray:
    """``[...]`` bool: every entry of ``z [..., P]`` inside its physical bounds (jittable)."""
    return jnp.all((z >= spec.low) & (z <= spec.high), axis=-1)


@dataclasses.dataclass(frozen=True)
class Subspace:
    """A subset of named parameters, e.g. the ones a DR distribution randomises.

    ``expand(z_sub [..., K], base [P]) -> [..., P]`` writes the subset into a full vector.
    """

    spec: ParamSpec
    names: tuple[str, ...]

    def __post_init__(self):
        for n in self.names:
            self.spec.index(n)  # raises with the list of known names

    @property
    def idx(self) -> np.ndarray:
        return self.spec.indices(self.names)

    def __len__(self) -> int:
        return len(self.names)

    @property
    def low(self) -> np.ndarray:
        return self.spec.low[self.idx]

    @property
    def high(self) -> np.ndarray:
        return self.spec.high[self.idx]

    @property
    def default(self) -> np.ndarray:
        return self.spec.default[self.idx]

    def expand(self, z_sub: jnp.ndarray, base=None) -> jnp.ndarray:
        base = jnp.asarray(self.spec.default if base is None else base)
        full = jnp.broadcast_to(base, z_sub.shape[:-1] + base.shape)
        return full.at[..., self.idx].set(z_sub)

    def take(self, z: jnp.ndarray) -> jnp.ndarray:
        return z[..., self.idx]
