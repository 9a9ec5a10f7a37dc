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
