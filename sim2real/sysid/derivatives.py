"""Smoothed derivatives of sampled positions (Savitzky-Golay), for states and inverse dynamics."""
from __future__ import annotations

import numpy as np
from scipy.signal import savgol_filter


def window_for(dt: float, seconds: float = 0.02, minimum: int = 7) -> int:
    """Odd window length covering about ``seconds`` of samples."""
    n = max(minimum, int(round(seconds / dt)))
    return n + 1 if n % 2 == 0 else n


def smooth_derivatives(x: np.ndarray, dt: float, window: int, order: int = 3):
    """``x [T, n]`` -> ``(x_smooth, x_dot, x_ddot)``, each ``[T, n]`` (local cubic fits)."""
    window = min(window, len(x) - (1 - len(x) % 2))
    kw = dict(window_length=window, polyorder=min(order, window - 1), axis=0, mode="interp")
    return (savgol_filter(x, deriv=0, **kw), savgol_filter(x, deriv=1, delta=dt, **kw),
            savgol_filter(x, deriv=2, delta=dt, **kw))


def align_to_model(q, dq, ddq, dt: float, timestep: float, rk4: bool):
    """Smoothed (central) derivatives -> the states and accelerations a discrete model step sees.

    The command recorded at sample ``k`` is held over ``[t_k, t_k + dt]``. With MuJoCo's
    semi-implicit Euler at ``n = dt / h`` physics steps per sample, the central second
    difference at ``k`` is ``(1 - w) a_{k-1} + w a_k`` with ``w = (n + 1) / 2n`` (exactly the
    acceleration of command ``k`` for ``n = 1``; the midpoint mix of continuous time as
    ``n`` grows, and for RK4), so the signals are read ``s = 1 - w`` samples later; and the
    velocity *state* lags the central difference by ``h/2 * ddq``. Without this, predictions
    from measured states start from a biased velocity, and the equation error pairs each
    command with a blend of the neighbouring steps' accelerations.
    All arrays ``[T, n]``; returns ``(q, dq, ddq)`` of the same shapes (last row repeated).
    """
    n = max(1, int(round(dt / timestep)))
    s = 0.5 if rk4 else (n - 1) / (2 * n)
    nxt = lambda x: np.concatenate([x[1:], x[-1:]])  # noqa: E731
    shift = lambda x: x if s == 0 else (1 - s) * x + s * nxt(x)  # noqa: E731
    q, dq, ddq = shift(q), shift(dq), shift(ddq)
    return q, velocity_state(dq, ddq, timestep, rk4), ddq


def velocity_state(dq, ddq, timestep: float, rk4: bool):
    """Central-difference velocity -> the velocity *state* of MuJoCo's integrator: semi-implicit
    Euler's lags it by ``h/2 * ddq`` (physics step ``h``); RK4's is the continuous one."""
    return dq if rk4 else dq - 0.5 * timestep * ddq
