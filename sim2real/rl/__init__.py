"""Pure-JAX PPO with MLP, context-conditioned and LSTM policies."""
from __future__ import annotations

from sim2real._lazy import exports

# public name -> "module:attribute"
_EXPORTS = {
    "PPO": "sim2real.rl.ppo:PPO",
    "PPOConfig": "sim2real.rl.ppo:PPOConfig",
    "PPOState": "sim2real.rl.ppo:PPOState",
}
__getattr__, __dir__, __all__ = exports(__name__, _EXPORTS)
