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
training recordings' validation tails), where its drift must explain ``min_explained`` of
``W``'s variance in every one.
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
        training fit's residual, samples taken as correlated over ``window`` seconds).
      explained: ``[R]`` fraction of ``W``'s variance its drift explains on each check recording.
      train_explained: the same on the training recordings (the fit's own).
    """

    candidate: object
    value: float
    std: float
    explained: list
    train_explained: list

    @property
    def worst(self) -> float:
        return float(min(self.explained)) if self.explained else float("nan")


def _work(system, z, trajs, stride: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per trajectory: ``(t [N], r [N, nv], v [N, nv])`` on every ``stride``-th sample away from
    the smoothing edges."""
    idx = [np.arange(tr.window, len(tr) - tr.window, stride) for tr in trajs]
    out = []
    for tr, ix in zip(trajs, idx):
        res = invdyn.residual(system, z, [tr], [ix])
        out.append((tr.time[ix], res["r"], res["v"]))
    return out


def _integral(t, r, v):
    return cumulative_trapezoid(np.sum(r * v, 1), t, initial=0.0)


def scan(system, z, train, check, candidates, spec, *, max_rows: int = 12000) -> list[Finding]:
    """Judge every dissipative candidate of ``candidates`` on top of model ``z``.

    ``train``, ``check``: trajectories (``check`` may be parts of ``train``'s recordings);
    ``spec``: the system's parameter spec (the candidates' parameters' indices and neutral values).
    Returns the findings, best (largest worst-recording ``explained``) first.
    """
    cands = [c for c in candidates if c.effect in DISSIPATIVE]
    if not cands or not train or not check:
        return []
    total = sum(len(tr) for tr in train + check)
    stride = max(1, total // max_rows)
    base_tr, base_ck = _work(system, z, train, stride), _work(system, z, check, stride)
    W_tr = [_integral(*b) for b in base_tr]
    W_ck = [_integral(*b) for b in base_ck]
    out = []
    for c in cands:
        i = spec.index(c.params[0])
        unit = float(c.scales[0])
        z1 = np.array(z, float).copy()
        z1[i] = z1[i] + unit
        # the candidate's force at size ``unit`` is what it takes off the residual (the residual is
        # linear in a viscous or Coulomb level: forward and inverse dynamics, no integration)
        P_tr = [(_integral(t, r0 - r1, v)) / unit for (t, r0, v), (_, r1, _) in zip(base_tr, _work(system, z1, train, stride))]
        P_ck = [(_integral(t, r0 - r1, v)) / unit for (t, r0, v), (_, r1, _) in zip(base_ck, _work(system, z1, check, stride))]
        # W = a_r + c Phi on each recording (a_r: the integral's start, free), c >= 0
        num = sum(float(np.dot(P - P.mean(), W - W.mean())) for P, W in zip(P_tr, W_tr))
        den = sum(float(np.dot(P - P.mean(), P - P.mean())) for P in P_tr)
        if den <= 0 or not np.isfinite(num):
            continue
        cval = max(num / den, 0.0)
        lo, hi = c.search[0]
        cval = float(np.clip(z[i] + cval, lo, hi) - z[i])

        def explained(Ps, Ws):
            f = []
            for P, W in zip(Ps, Ws):
                e0 = W - W.mean()
                e1 = e0 - cval * (P - P.mean())
                f.append(float(1.0 - np.sum(e1**2) / max(np.sum(e0**2), 1e-300)))
            return f

        # standard error: the residual's variance, with samples correlated over a tenth of a
        # recording (a drift's noise is smooth), so the effective count is small
        res = np.concatenate([(W - W.mean()) - cval * (P - P.mean()) for P, W in zip(P_tr, W_tr)])
        n_eff = max(len(P_tr) * 10 - 1, 1)
        std = float(np.sqrt(np.mean(res**2) / den * len(res) / n_eff)) if den > 0 else float("inf")
        out.append(Finding(c, float(z[i] + cval), std, explained(P_ck, W_ck), explained(P_tr, W_tr)))
    out.sort(key=lambda f: -f.worst)
    return out
