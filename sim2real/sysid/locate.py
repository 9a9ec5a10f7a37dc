"""Locate a sim-vs-real mismatch: which signals, which time windows, which regimes.

Two complementary residuals, both usable where an open-loop replay diverges:

* prediction errors of short-horizon simulations started from measured states (per signal),
* inverse-dynamics residuals (per joint, in force units).

Regimes are sample masks built from the measured motion and the commands; a regime's *excess*
is the residual's RMS inside it over its RMS everywhere (> 1: the mismatch concentrates there).
The *offset ratio* |mean| / RMS of a residual near 1 says the mismatch is a constant bias.
"""
from __future__ import annotations

import numpy as np

from sim2real.sysid.discrepancy import nrmse  # noqa: F401  (shared with SimOpt; re-exported)


def regimes(v: np.ndarray, a: np.ndarray, force: np.ndarray, force_limit: float | None,
            ctrl: np.ndarray, ctrl_bounds: tuple[float, float] | None, w: int) -> dict[str, np.ndarray]:
    """Boolean masks ``[T]`` of motion regimes for one joint and its actuator.

    Args:
      v, a: smoothed joint velocity and acceleration ``[T]``.
      force: modelled actuator force ``[T]``; force_limit: its clamp (None if unlimited).
      ctrl: command ``[T]``; ctrl_bounds: its range (None if unlimited).
      w: samples on each side counted as "near" a reversal.
    """
    vmax = np.percentile(np.abs(v), 95) + 1e-12
    amax = np.percentile(np.abs(a), 95) + 1e-12
    out = {
        "velocity_reversal": _near(np.diff(np.sign(v)) != 0, w) | (np.abs(v) < 0.03 * vmax),
        "high_speed": np.abs(v) > 0.6 * vmax,
        "high_acceleration": np.abs(a) > 0.6 * amax,
        "command_reversal": _near(np.diff(np.sign(force)) != 0, w),
    }
    sat = np.zeros_like(v, bool)
    if force_limit is not None and np.isfinite(force_limit):
        sat |= np.abs(force) >= 0.98 * force_limit
    if ctrl_bounds is not None:
        lo, hi = ctrl_bounds
        span = hi - lo
        sat |= (ctrl <= lo + 0.01 * span) | (ctrl >= hi - 0.01 * span)
    out["saturated_command"] = sat
    out["steady"] = (np.abs(v) < 0.03 * vmax) & (np.abs(a) < 0.05 * amax)
    return out


def _near(events: np.ndarray, w: int) -> np.ndarray:
    """``events [T-1]`` between samples -> ``[T]`` mask of samples within ``w`` of one."""
    e = np.concatenate([events, [False]]).astype(float)
    k = np.ones(2 * w + 1)
    return np.convolve(e, k, mode="same") > 0


def regime_table(residual: np.ndarray, masks: dict[str, np.ndarray], min_fraction: float = 0.01,
                 fitted: np.ndarray | None = None) -> dict:
    """Per regime: fraction of samples, RMS, and excess (RMS in regime / RMS overall); with
    ``fitted`` (the fitted model's residual on the same samples) also its RMS there, ``rms_fitted``.
    A regime with fewer than ``min_fraction`` of the samples gets None: its RMS says little."""
    total = float(np.sqrt(np.mean(residual**2))) + 1e-300
    out = {}
    for name, m in masks.items():
        frac = float(m.mean())
        if frac < min_fraction:
            out[name] = {"fraction": frac, "rms": None, "excess": None}
            continue
        rms = float(np.sqrt(np.mean(residual[m] ** 2)))
        out[name] = {"fraction": round(frac, 4), "rms": rms, "excess": round(rms / total, 3)}
        if fitted is not None:
            out[name]["rms_fitted"] = float(np.sqrt(np.mean(fitted[m] ** 2)))
    return out


def offset_ratio(residual: np.ndarray) -> float:
    return float(abs(residual.mean()) / (np.sqrt(np.mean(residual**2)) + 1e-300))


def windows(time: np.ndarray, err: np.ndarray, scale: float, n: int) -> list[dict]:
    """Split a recording into ``n`` windows; NRMSE of ``err [T]`` (NaN where not predicted) in each."""
    edges = np.linspace(0, len(time), n + 1).astype(int)
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        e = err[a:b]
        e = e[np.isfinite(e)]
        if len(e) == 0:
            continue
        out.append({"t_start": float(time[a]), "t_end": float(time[b - 1]),
                    "nrmse": nrmse(e, 0.0, scale)})
    return out
