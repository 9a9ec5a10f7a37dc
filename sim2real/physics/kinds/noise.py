"""Observation noise: white noise on every observation (``Env._observe`` adds it, after sensing)."""
from __future__ import annotations

from sim2real.physics.kinds.base import Kind


class ObservationNoise(Kind):
    owns = ("obs_noise",)
    order = 95
