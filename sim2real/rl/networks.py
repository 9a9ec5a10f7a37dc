"""Actor-critic networks: MLP, context-conditioned MLP (pi(a | s, z)), and LSTM.

All policies share one call signature so rollout and PPO do not care which is which::

    (mean [A], log_std [A], value []), carry = net.apply(params, obs [O], ctx [K], carry, reset [])

``ctx`` is the normalised physics sub-vector (empty unless the policy is context-conditioned);
``carry`` is the recurrent state (an empty array for feed-forward nets); ``reset`` zeroes it at
episode starts. Actions are Gaussian in [-1, 1]-scaled units; the env maps them to ctrl ranges.
"""
from __future__ import annotations

import dataclasses
from typing import Sequence

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np


@dataclasses.dataclass(frozen=True)
class NetConfig:
    """Network shape.

    Attributes:
      kind: ``mlp`` | ``lstm``. A context-conditioned MLP is ``mlp`` with ``use_context``.
      hidden: hidden layer widths of actor and critic (separate trunks).
      lstm_size: LSTM cell size (``kind == 'lstm'``).
      use_context: feed the normalised physics vector z to actor and critic (LSDR's pi(a|s,z)).
      init_log_std: initial log standard deviation of the Gaussian policy.
      activation: ``tanh`` | ``relu`` | ``swish``.
    """

    kind: str = "mlp"
    hidden: tuple[int, ...] = (64, 64)
    lstm_size: int = 64
    use_context: bool = False
    init_log_std: float = -0.5
    activation: str = "tanh"


_ACT = {"tanh": nn.tanh, "relu": nn.relu, "swish": nn.swish}


class _Trunk(nn.Module):
    hidden: Sequence[int]
    out: int
    act: str
    out_scale: float

    @nn.compact
    def __call__(self, x):
        for h in self.hidden:
            x = _ACT[self.act](nn.Dense(h, kernel_init=nn.initializers.orthogonal(np.sqrt(2)))(x))
        return nn.Dense(self.out, kernel_init=nn.initializers.orthogonal(self.out_scale))(x)


class ActorCritic(nn.Module):
    cfg: NetConfig
    action_size: int

    @nn.compact
    def __call__(self, obs, ctx, carry, reset):
        cfg = self.cfg
        x = jnp.concatenate([obs, ctx], -1) if cfg.use_context else obs
        if cfg.kind == "lstm":
            cell = nn.OptimizedLSTMCell(cfg.lstm_size)
            c, h = jnp.split(carry, 2, axis=-1)
            keep = 1.0 - reset.astype(x.dtype)[..., None]
            (c, h), y = cell((c * keep, h * keep), x)
            carry = jnp.concatenate([c, h], -1)
            x = jnp.concatenate([x, y], -1)
        elif cfg.kind != "mlp":
            raise ValueError(f"unknown network kind '{cfg.kind}' (mlp, lstm)")
        mean = _Trunk(cfg.hidden, self.action_size, cfg.activation, 0.01, name="actor")(x)
        value = _Trunk(cfg.hidden, 1, cfg.activation, 1.0, name="critic")(x)[..., 0]
        log_std = self.param("log_std", nn.initializers.constant(cfg.init_log_std), (self.action_size,))
        return (mean, jnp.broadcast_to(log_std, mean.shape), value), carry


def carry_size(cfg: NetConfig) -> int:
    return 2 * cfg.lstm_size if cfg.kind == "lstm" else 0


def init_params(key, cfg: NetConfig, obs_size: int, ctx_size: int, action_size: int):
    net = ActorCritic(cfg, action_size)
    carry = jnp.zeros((carry_size(cfg),))
    return net, net.init(key, jnp.zeros(obs_size), jnp.zeros(ctx_size), carry, jnp.zeros((), bool))


def gaussian_log_prob(mean, log_std, action):
    """``[..., A] -> [...]``"""
    z = (action - mean) / jnp.exp(log_std)
    return jnp.sum(-0.5 * z**2 - log_std - 0.5 * jnp.log(2 * jnp.pi), axis=-1)


def gaussian_entropy(log_std):
    return jnp.sum(log_std + 0.5 * jnp.log(2 * jnp.pi * jnp.e), axis=-1)


def sample_action(key, mean, log_std):
    return mean + jnp.exp(log_std) * jax.random.normal(key, mean.shape)
