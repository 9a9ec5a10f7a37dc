"""The one training driver (chunks, resume, signals) and the run folder it writes, below it the
checkpoints. Every outer loop of ``sim2real.algos`` is trained here."""
from __future__ import annotations

from sim2real._lazy import exports

# public name -> "module:attribute"
_EXPORTS = {
    "TrainConfig": "sim2real.training.runs:TrainConfig",
    "train": "sim2real.training.driver:train",
    "load_policy": "sim2real.training.runs:load_policy",
    "load_run": "sim2real.training.runs:load_run",
    "summary": "sim2real.training.runs:summary",
}
__getattr__, __dir__, __all__ = exports(__name__, _EXPORTS)
