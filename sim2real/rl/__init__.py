"""Pure-JAX PPO with MLP, context-conditioned and LSTM policies."""
