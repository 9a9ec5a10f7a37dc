"""What a user does with a trained run: evaluate it over a physics grid, record it on a target
(native MuJoCo or the env), and the record -> diagnose -> retrain loop."""
from __future__ import annotations

from sim2real._lazy import exports

# public name -> "module:attribute"
_EXPORTS = {
    "EvaluateConfig": "sim2real.tools.evaluate:EvaluateConfig",
    "evaluate_run": "sim2real.tools.evaluate:evaluate_run",
    "record_run": "sim2real.tools.record:from_run",
    "save_recordings": "sim2real.tools.record:save",
    "loop_iteration": "sim2real.tools.loop:iteration",
}
__getattr__, __dir__, __all__ = exports(__name__, _EXPORTS)
