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

    The command recorded at sample ``k`` is held over ``[t_k, t_k + dt]``. For MuJoCo's
    semi-implicit Euler (and implicit) integrators, with physics step ``h``, the velocity
    *state* at sample ``k`` lags the central difference by ``h/2 * ddq`` and the acceleration
    that command ``k`` causes is the central second difference at ``k + 1``; without this the
    equation error pairs each command with the previous step's acceleration (a spurious
    one-sample delay). For RK4 (continuous time) the step is evaluated at the midpoint.
    All arrays ``[T, n]``; returns ``(q, dq, ddq)`` of the same shapes (last row repeated).
    """
    nxt = lambda x: np.concatenate([x[1:], x[-1:]])  # noqa: E731
    if rk4:
        return 0.5 * (q + nxt(q)), 0.5 * (dq + nxt(dq)), 0.5 * (ddq + nxt(ddq))
    return q, dq - 0.5 * timestep * ddq, nxt(ddq)
