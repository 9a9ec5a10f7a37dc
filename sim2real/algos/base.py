"""What every outer-loop algorithm shares: the DR box config and the PPO it trains."""
from __future__ import annotations

import dataclasses
from typing import Any

import jax.numpy as jnp
import numpy as np

from sim2real.envs.base import Env
from sim2real.physics.params import Subspace


@dataclasses.dataclass(frozen=True)
class DRConfig:
    """Which physics parameters are randomised, over which box, and fixed values for the rest.

    Attributes:
      params: names of randomised parameters (empty: fixed physics).
      low, high: box bounds, one per name (may reach past the physical bounds: values are
        clipped to them in the simulator, see README "bounds rule").
      fixed: name -> value for parameters held at a non-default value.
    """

    params: tuple[str, ...] = ()
    low: tuple[float, ...] = ()
    high: tuple[float, ...] = ()
    fixed: dict[str, float] = dataclasses.field(default_factory=dict)


class DRSpace:
    """The randomised sub-vector: ``expand(z_sub [K]) -> z [P]`` on top of the fixed base."""

    def __init__(self, env: Env, cfg: DRConfig):
        if not (len(cfg.params) == len(cfg.low) == len(cfg.high)):
            raise ValueError(f"dr.params, dr.low and dr.high must have the same length "
                             f"(got {len(cfg.params)}, {len(cfg.low)}, {len(cfg.high)})")
        for n, lo, hi in zip(cfg.params, cfg.low, cfg.high):
            if not lo < hi:
                raise ValueError(f"dr box for '{n}': low {lo} must be below high {hi}")
        self.env = env
        self.sub = Subspace(env.spec, tuple(cfg.params))
        self.base = env.z_of(**{k: float(v) for k, v in cfg.fixed.items()})
        self.low = np.asarray(cfg.low, np.float32)
        self.high = np.asarray(cfg.high, np.float32)

    def __len__(self) -> int:
        return len(self.sub)

    def expand(self, z_sub):
        return self.sub.expand(z_sub, self.base)

    @property
    def names(self) -> tuple[str, ...]:
        return self.sub.names


def metrics_mean(m: dict[str, Any]) -> dict[str, Any]:
    return {k: jnp.mean(v) for k, v in m.items()}
