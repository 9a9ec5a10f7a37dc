"""Dissipation that only shows over seconds, found by the work it does over whole recordings.

Short predictions (``shooting``) cannot see a loss of 2% of the energy per second, and long
ones cannot be made of a chaotic or unstable system: they diverge from the data whatever the
friction. The work a missing dissipative force does can still be measured along the *measured*
motion. The inverse-dynamics residual ``r(t) [nv]`` (``invdyn.residual``: the force the model
gives less the force the motion needs) times the velocity, integrated,

    W(t) = int_0^t r . v dt  =  -(work the model's forces miss)  =  sum_i c_i Phi_i(t) + noise,

where ``Phi_i(t)`` is the same integral of candidate ``i``'s force at unit size (a viscous
damping: ``int v_j^2``; a Coulomb friction: ``int |v_j|``). Summed over the joints, the
inertial and gravity terms of ``r . v`` telescope to the change of the model's energy, so
the noise of twice-differentiated positions does not accumulate over the integral, and a
dissipation shows as a drift that grows with time. Each candidate's size ``c >= 0`` is fitted
on the training recordings; it is judged on the check recordings (held-out ones, else the
training recordings' validation tails), where its drift must explain a fraction of ``W``'s
variance in every one (``DiagnoseConfig.energy_explained``).
"""
from __future__ import annotations

import dataclasses

import numpy as np
from scipy.integrate import cumulative_trapezoid

from sim2real.sysid import invdyn

DISSIPATIVE = ("viscous_damping", "coulomb_friction")
"""Effects whose force always opposes the motion: the ones the energy balance can size."""


@dataclasses.dataclass
class Finding:
    """One candidate judged by the energy balance.

    Attributes:
      candidate: the ``candidates.Candidate``.
      value: its fitted size (its first parameter's units); ``std``: standard error (from the
        training fit's residual, samples taken as correlated over a tenth of a recording).
      explained: ``[R]`` fraction of ``W``'s variance its drift explains on each check recording.
      train_explained: the same on the training recordings (the fit's own).
      curves: per check recording, ``{"t", "missing", "explained"}`` (s, J; at most 400 points):
        the work the model misses and what the fit gives (the model's own parameters re-sized
        and the candidate), each from the recording's mean, for the report's figure.
    """

    candidate: object
    value: float
    std: float
    explained: list
    train_explained: list
    curves: list = dataclasses.field(default_factory=list)

    @property
    def worst(self) -> float:
        return float(min(self.explained)) if self.explained else float("nan")


def _work(system, z, trajs, stride: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per trajectory: ``(t [N], r [N, nv], v [N, nv])`` on every ``stride``-th sample away from
    the smoothing edges."""
    out = []
    for tr in trajs:
        ix = np.arange(tr.window, len(tr) - tr.window, stride)
        res = invdyn.residual(system, z, [tr], [ix])
        out.append((tr.time[ix], res["r"], res["v"]))
    return out


def _power(r, v):
    return np.sum(r * v, 1)


def _cumulative(t, p, keep):
    """``int_0^t p`` over the samples ``keep`` (rejected stretches add nothing)."""
    return cumulative_trapezoid(np.where(keep, p, 0.0), t, initial=0.0)


def _lsq(X: list, W: list, nonneg_last: bool):
    """Least squares of ``W_r = a_r + X_r b`` over recordings (``X_r [N, k]``, intercepts free);
    the last coefficient kept >= 0 when ``nonneg_last`` (dropped to 0 and the rest re-solved)."""
    A = np.concatenate([x - x.mean(0) for x in X])
    y = np.concatenate([w - w.mean() for w in W])
    b = np.linalg.lstsq(A, y, rcond=None)[0] if A.shape[1] else np.zeros(0)
    if nonneg_last and A.shape[1] and b[-1] < 0:
        b = np.zeros(A.shape[1])
        if A.shape[1] > 1:
            b[:-1] = np.linalg.lstsq(A[:, :-1], y, rcond=None)[0]
    return b, A, y


def _sse(X: list, W: list, b) -> list:
    return [float(np.sum(((w - w.mean()) - (x - x.mean(0)) @ b) ** 2)) for x, w in zip(X, W)]


def _explained(sse: list, sse0: list) -> list:
    """Per recording: the fraction of the baseline's squared residual ``sse0`` a fit removes."""
    return [float(1.0 - a / max(o, 1e-300)) for a, o in zip(sse, sse0)]


REJECT = 8.0
"""A block of 0.1 s is dropped from the balance when its missing work departs this many robust
standard deviations from what the regressors give (a glitch, not a dissipation)."""


def _glitches(t, P, v, coef, block: int, scale=None):
    """Samples to keep, per recording: blocks of ``block`` samples whose missing work ``P[:, 0]``
    departs from what every regressor together gives (``P[:, 1:] @ coef``) by more than
    ``REJECT`` times the typical departure of a moving block, per unit of speed, are dropped (a sensor's glitch:
    on the DFKI pendulum a fall from the top at 13 rad/s with the torque reading +1 N m, 9.6 J
    in half a second). Returns ``(keep per recording, scale)``."""
    res, moving, spans = [], [], []
    for tk, Pk, vk in zip(t, P, v):
        dt = np.gradient(tk)
        K = len(tk) // block
        for k in range(K):
            sl = slice(k * block, (k + 1) * block)
            res.append(float(np.sum((Pk[sl, 0] - Pk[sl, 1:] @ coef) * dt[sl])))
            moving.append(float(np.mean(np.abs(vk[sl]))))
        spans.append(K)
    res, moving = np.array(res), np.array(moving)
    # the noise of a block's work grows with its speed (differentiated positions' noise times
    # the velocity): departures are compared per unit of the block's mean speed
    floor = 0.05 * (moving.max() if len(moving) else 0.0)
    res = res / np.maximum(moving, max(floor, 1e-12))
    if scale is None:
        m = moving > floor
        scale = 1.4826 * float(np.median(np.abs(res[m] - np.median(res[m])))) if m.any() else 0.0
    out, i = [], 0
    for tk, K in zip(t, spans):
        keep = np.ones(len(tk), bool)
        for k in range(K):
            if scale > 0 and abs(res[i]) > REJECT * scale:
                # with the blocks either side: a glitch's edges fall inside them, diluted
                keep[max(k - 1, 0) * block: (k + 2) * block] = False
            i += 1
        out.append(keep)
    return out, scale


def scan(system, z, train, check, candidates, spec, *, nuisance=(), max_rows: int = 12000):
    """Judge every dissipative candidate of ``candidates`` on top of model ``z``.

    ``train``, ``check``: trajectories (``check`` may be parts of ``train``'s recordings);
    ``spec``: the system's parameter spec (the candidates' parameters' indices and neutral values);
    ``nuisance``: ``{name: unit}`` of the model's own parameters (a declared damping or friction loss),
    re-sized either way beside every candidate: a candidate must explain what re-sizing them
    does not. Returns ``(findings, best -- largest worst-recording ``explained`` -- first;
    seconds dropped as glitches per recording, training then check)``.
    """
    cands = [c for c in candidates if c.effect in DISSIPATIVE]
    if not cands or not train or not check:
        return [], []
    total = sum(len(tr) for tr in train + check)
    stride = max(1, total // max_rows)
    names = list(dict(nuisance)) + [c.params[0] for c in cands]
    units = list(dict(nuisance).values()) + [float(c.scales[0]) for c in cands]

    def integrands(trajs):
        """Per trajectory: ``(t [N], v [N, nv], P [N, 1 + len(names)])``: the missing power, then
        every parameter's power per unit of it."""
        base = _work(system, z, trajs, stride)
        cols = [[_power(r, v)] for _, r, v in base]
        for name, unit in zip(names, units):
            z1 = np.array(z, float).copy()
            z1[spec.index(name)] += unit
            for col, (_, r0, v), (_, r1, _) in zip(cols, base, _work(system, z1, trajs, stride)):
                col.append(_power(r0 - r1, v) / unit)
        return [b[0] for b in base], [b[2] for b in base], [np.stack(c, 1) for c in cols]

    t_tr, v_tr, P_tr = integrands(train)
    t_ck, v_ck, P_ck = integrands(check)
    block = max(3, int(round(0.1 / max(np.median(np.diff(t_tr[0])), 1e-9))))
    # glitches: blocks no combination of the regressors comes near (fitted on the training blocks)
    A = np.concatenate([np.add.reduceat(p[:, 1:] * np.gradient(tk)[:, None], np.arange(0, len(tk), block))
                        for tk, p in zip(t_tr, P_tr)])
    y = np.concatenate([np.add.reduceat(p[:, 0] * np.gradient(tk), np.arange(0, len(tk), block))
                        for tk, p in zip(t_tr, P_tr)])
    coef = np.linalg.lstsq(A, y, rcond=None)[0]
    for _ in range(2):
        keep_tr, scale = _glitches(t_tr, P_tr, v_tr, coef, block)
        kb = np.concatenate([np.logical_and.reduceat(k, np.arange(0, len(k), block)) for k in keep_tr])
        coef = np.linalg.lstsq(A[kb], y[kb], rcond=None)[0]
    keep_ck, _ = _glitches(t_ck, P_ck, v_ck, coef, block, scale)
    dropped = [float(np.sum(np.gradient(tk)[~k])) for tk, k in zip(t_tr + t_ck, keep_tr + keep_ck)]

    def cum(ts, Ps, keeps, cols):
        """Per recording: ``[N, len(cols)]`` integrals of the integrand columns ``cols``."""
        return [np.stack([_cumulative(tk, p[:, j], k) for j in cols], 1) if len(cols) else np.zeros((len(tk), 0))
                for tk, p, k in zip(ts, Ps, keeps)]

    W_tr = [w[:, 0] for w in cum(t_tr, P_tr, keep_tr, [0])]
    W_ck = [w[:, 0] for w in cum(t_ck, P_ck, keep_ck, [0])]
    nn = len(dict(nuisance))
    Xn_tr = cum(t_tr, P_tr, keep_tr, list(range(1, 1 + nn)))
    Xn_ck = cum(t_ck, P_ck, keep_ck, list(range(1, 1 + nn)))
    # what re-sizing the model's own parameters explains (fitted on the training recordings)
    bn, _, _ = _lsq(Xn_tr, W_tr, False)
    sse0_tr, sse0_ck = _sse(Xn_tr, W_tr, bn), _sse(Xn_ck, W_ck, bn)
    out = []
    for j, c in enumerate(cands):
        i = spec.index(c.params[0])
        X_tr = [np.column_stack([n, p]) for n, p in zip(Xn_tr, cum(t_tr, P_tr, keep_tr, [1 + nn + j]))]
        X_ck = [np.column_stack([n, p]) for n, p in zip(Xn_ck, cum(t_ck, P_ck, keep_ck, [1 + nn + j]))]
        b, A_, y_ = _lsq(X_tr, W_tr, True)
        if not np.all(np.isfinite(b)):
            continue
        lo, hi = c.search[0]
        b[-1] = float(np.clip(z[i] + b[-1], lo, hi) - z[i])
        sse_tr, sse_ck = _sse(X_tr, W_tr, b), _sse(X_ck, W_ck, b)
        # standard error: the residual's variance, with samples correlated over a tenth of a
        # recording (a drift's noise is smooth), so the effective count is small
        res = y_ - A_ @ b
        n_eff = max(len(train) * 10 - A_.shape[1], 1)
        try:
            cov = np.linalg.inv(A_.T @ A_) * float(np.sum(res**2)) / n_eff
            std = float(np.sqrt(max(cov[-1, -1], 0.0)))
        except np.linalg.LinAlgError:
            std = float("inf")
        curves = []
        for tk, w, x in zip(t_ck, W_ck, X_ck):
            k = np.unique(np.linspace(0, len(tk) - 1, min(400, len(tk))).astype(int))
            curves.append({"t": tk[k].tolist(), "missing": (w - w.mean())[k].tolist(),
                           "explained": ((x - x.mean(0)) @ b)[k].tolist()})
        out.append(Finding(c, float(z[i] + b[-1]), std, _explained(sse_ck, sse0_ck), _explained(sse_tr, sse0_tr),
                           curves))
    out.sort(key=lambda f: -f.worst)
    return out, dropped
