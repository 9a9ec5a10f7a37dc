"""Fit every candidate on inverse-dynamics residuals and rank them on held-out rows.

For each candidate the nominal parameters and the effect's parameters are fitted together by
bounded linear least squares on the residual's finite-difference regressors (exact for the
linear parameters; one Gauss-Newton refinement for the sensor offset); a nonlinear parameter
(delay, lag, saturation, backlash width) is searched on a grid with the linear fit redone at
every point. Why least squares on the equation error rather than CMA-ES or gradients through a
simulation: it is closed-form, deterministic and fast enough to try ~20 hypotheses on 25k
samples in seconds, and it needs no stable open-loop replay. The selected model is then checked
by *simulation* on held-out recordings (``simulate.py``).

Ranking: BIC on the training rows (with an effective sample count that accounts for the
smoothing window's correlation) and RMSE on held-out rows (the last ``val_fraction`` of each
training recording) screen the candidates; the best few are then verified by simulated
short-horizon predictions on those held-out rows (``rank``), which average the measurement
noise out instead of differentiating it twice.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from scipy.optimize import lsq_linear

from sim2real.sysid.candidates import Candidate
from sim2real.sysid.invdyn import InverseDynamics


@dataclasses.dataclass
class Fit:
    """A fitted candidate.

    Attributes:
      candidate: the hypothesis.
      z: ``[P]`` fitted physics vector.
      params: fitted values of the parameters it set, by spec name (nominal ones included).
      std: their standard deviations (least-squares covariance, inflated for correlated rows).
      train_rmse, val_rmse: residual RMSE (per-DOF normalised units) on train / held-out rows.
      bic: Bayesian information criterion on the training rows.
    """

    candidate: Candidate
    z: np.ndarray
    params: dict[str, float]
    std: dict[str, float]
    train_rmse: float
    val_rmse: float
    bic: float
    alternatives: list = dataclasses.field(default_factory=list)


def _step_for(spec, name: str) -> float:
    p = spec[name]
    if p.kind in ("body_mass", "actuator_gain", "actuator_kv", "dof_damping"):
        return 1e-3 * max(abs(p.default), 1e-3)
    if p.kind == "sensor_offset":
        return 1e-4
    return 1.0  # linear in these: any step is exact


class Identifier:
    """Builds the regressors once and fits candidates on them.

    Args:
      idyn: residual builder over the training recordings.
      val_fraction: tail of each training recording held out for ranking.
      window: smoothing window (samples); rows within a window are correlated.
    """

    def __init__(self, idyn: InverseDynamics, val_fraction: float = 0.3, window: int = 21):
        self.idyn, self.spec, self.window = idyn, idyn.sys.spec, window
        self.z0 = np.array(self.spec.default, np.float32)
        self.nominal = list(idyn.sys.nominal)
        r0 = idyn.residual(self.z0)
        n = len(r0)
        rec = idyn.rows()
        self.val = np.zeros(n, bool)
        for k in np.unique(rec):
            idx = np.where(rec == k)[0]
            self.val[idx[int(len(idx) * (1 - val_fraction)):]] = True
        # normalise each DOF by the nominal residual's spread so every DOF counts alike

        self.r0 = r0
        self.dq = idyn.stacked("dq")
        # Elements where a joint (nearly) stands still are left out of every fit: there a dry
        # friction force is anywhere in [-Fc, Fc] (stiction), so no friction model is an equation
        # there, and the derivative of a noisy standstill is noise. The threshold is 2% of the
        # joint's typical speed; every candidate is fitted and scored on the same elements.
        v_min = 0.02 * np.percentile(np.abs(self.dq), 95, axis=0)
        self.use = np.abs(self.dq) >= v_min
        # Rows where a limited joint is at (or within 2% of its range from) a limit are left
        # out too: the limit's contact force is not a missing effect, and its soft-constraint
        # force is ill-determined from smoothed accelerations around an impact.
        m = idyn.sys.mj
        q = idyn.stacked("q")
        for j in range(m.njnt):
            if m.jnt_limited[j]:
                lo, hi = m.jnt_range[j]
                margin = 0.02 * (hi - lo)
                near = (q[:, m.jnt_qposadr[j]] < lo + margin) | (q[:, m.jnt_qposadr[j]] > hi - margin)
                # the smoothing window spreads an impact's acceleration over its neighbours
                near = np.convolve(near.astype(float), np.ones(2 * window + 1), "same") > 0
                self.use[near, :] = False
        # Each DOF's equations are normalised by the size of the forces in it (the spread of the
        # nominal inverse-dynamics force on the rows used), so every DOF counts alike in relative
        # terms. Not by the nominal residual: an unactuated DOF's equation is homogeneous in its
        # link's inertia, and a residual-based weight would reward shrinking that link to nothing.
        # (For an unactuated DOF the total is ~0 whatever the model, so the size is taken term by
        # term: inertial force M(q) ddq and bias force separately.)
        from sim2real.physics.model_apply import to_mjmodel

        mm = to_mjmodel(idyn.sys.physics, self.z0)
        qs, dqs, ddqs = idyn.stacked("q"), idyn.stacked("dq"), idyn.stacked("ddq")
        bias = idyn.inverse(mm, qs, dqs, np.zeros_like(ddqs))
        inertial = idyn.inverse(mm, qs, dqs, ddqs) - bias
        rows = self.use & ~self.val[:, None]
        self.scale = np.array([max(float(np.sqrt(inertial[rows[:, k], k].var() + bias[rows[:, k], k].var()))
                                   if rows[:, k].any() else 0.0, 1e-9) for k in range(inertial.shape[1])])
        self.cols = {}          # spec name -> full-residual regressor [n, nv]
        self.act_cols = {}      # spec name -> actuator-part regressor (re-computed under grid values)
        for name in self.nominal:
            self.cols[name] = self._nominal_column(name, self.z0)
        self._r_dyn0 = None

    def _nominal_column(self, name: str, z) -> np.ndarray:
        """Regressor of a nominal parameter at ``z``: gains act on the actuator part only."""
        parts = ("act",) if self.spec[name].kind in ("actuator_gain", "actuator_kv") else ("dyn",)
        return self.idyn.regressor(z, name, _step_for(self.spec, name), parts)

    # ------------------------------------------------------------------------------------------
    def column(self, name: str) -> np.ndarray:
        if name not in self.cols:
            self.cols[name] = self.idyn.regressor(self.z0, name, _step_for(self.spec, name))
        return self.cols[name]

    def _coulomb_columns(self, joint: str, two_sided: bool):
        m = self.idyn.sys.mj
        dof = m.jnt_dofadr[self.idyn.sys.joints.index(joint)]
        v = self.dq[:, dof]
        eps = self.idyn.sys.effects.cfg.coulomb_eps
        base = np.zeros_like(self.r0)
        base[:, dof] = -np.tanh(v / eps)
        if not two_sided:
            return [base]
        pos, neg = base.copy(), base.copy()
        pos[v < 0] = 0.0
        neg[v >= 0] = 0.0
        return [pos, neg]

    def _solve(self, r0, columns, names, lows, highs):
        """Bounded LS of ``r0 + X d = 0`` on training rows; returns (d, train rmse, val rmse, cov)."""
        X = np.stack([c / self.scale for c in columns], -1)  # [n, nv, k]
        y = -(r0 / self.scale)
        tr, va = self.use & ~self.val[:, None], self.use & self.val[:, None]  # [n, nv] elements
        Xt, yt = X[tr], y[tr]
        norm = np.maximum(np.linalg.norm(Xt, axis=0), 1e-12)
        res = lsq_linear(Xt / norm, yt, bounds=(np.asarray(lows) * norm, np.asarray(highs) * norm),
                         method="bvls" if Xt.shape[1] <= 8 else "trf")
        d = res.x / norm
        e_tr = yt - Xt @ d
        e_va = y[va] - X[va] @ d
        n_eff = max(len(yt) / self.window, Xt.shape[1] + 2)
        sigma2 = e_tr @ e_tr / max(len(yt) - Xt.shape[1], 1)
        try:
            cov = np.linalg.inv(Xt.T @ Xt) * sigma2 * len(yt) / n_eff
        except np.linalg.LinAlgError:
            cov = np.full((len(d), len(d)), np.nan)
        return d, float(np.sqrt(np.mean(e_tr**2))), float(np.sqrt(np.mean(e_va**2))), cov, len(yt)

    def _bic(self, rmse, n, k):
        n_eff = n / self.window
        return float(n_eff * np.log(rmse**2 + 1e-300) + k * np.log(n_eff))

    def fit(self, cand: Candidate) -> Fit:
        """Fit one candidate (grid search over its nonlinear parameter if it has one)."""
        if cand.grid_param is None:
            return self._fit_at(cand, self.z0, self.r0)
        i = self.spec.index(cand.grid_param)
        fits = []
        fits = [self._fit_grid_point(cand, i, g) for g in cand.grid]
        k = int(np.argmin([f.train_rmse for f in fits]))
        best = self._refine_grid(cand, i, fits[k], cand.grid[max(k - 1, 0)], cand.grid[min(k + 1, len(fits) - 1)])
        if cand.effect == "sensor_offset":
            # the nominal regressors (gravity terms) at the shifted positions, for the final fit
            best = self._fit_grid_point(cand, i, float(best.z[i]), fresh=True)
        # the grid neighbours of the equation-error optimum, for verification by simulation
        # (smoothing blurs command steps, which biases the equation error by a grid step or so)
        best.alternatives = [fits[j] for j in (k - 1, k + 1) if 0 <= j < len(fits)]
        return best

    def _refine_grid(self, cand: Candidate, i: int, best: Fit, lo: float, hi: float, evals: int = 10) -> Fit:
        """Bounded scalar search of the grid parameter between the best point's neighbours.

        The grids are coarse (geometric, ~30% apart): for a stiff servo a lag or delay 10% off
        leaves a residual larger than the one of a *different* timing effect at a lucky grid
        point, so the screen compares every candidate at its own optimum.
        """
        from scipy.optimize import minimize_scalar

        if not hi > lo:
            return best
        cache = {}

        def fit_at(g):
            if g not in cache:
                cache[g] = self._fit_grid_point(cand, i, g)
            return cache[g]

        res = minimize_scalar(lambda g: fit_at(float(g)).train_rmse, bounds=(lo, hi), method="bounded",
                              options={"maxiter": evals, "xatol": 1e-3 * (hi - lo)})
        f = fit_at(float(res.x))
        return f if f.train_rmse < best.train_rmse else best

    def _fit_grid_point(self, cand: Candidate, i: int, g: float, fresh: bool = False) -> Fit:
        """The candidate fitted with its grid parameter (index ``i``) held at ``g``."""
        z = self.z0.copy()
        z[i] = g
        return self._fit_at(cand, z, self._grid_residual(cand, z), regrid=True, fresh=fresh)

    def _grid_residual(self, cand: Candidate, z):
        """Residual at a grid point: delay, lag, saturation and backlash act on the actuator path
        only (the dynamics part is the nominal one); a sensor offset moves every position."""
        if cand.effect == "sensor_offset":
            return self.idyn.residual(z)
        return self._act_residual(z) + self._dyn_residual()

    def _dyn_residual(self):
        if self._r_dyn0 is None:
            self._r_dyn0 = self.idyn.residual(self.z0, parts=("dyn",))
        return self._r_dyn0

    def _act_residual(self, z):
        return self.idyn.residual(z, parts=("act",))

    def _fit_at(self, cand: Candidate, z, r0, regrid: bool = False, fresh: bool = False) -> Fit:
        """``fresh``: nominal regressors re-computed at ``z`` (not the cached ones at the nominal)."""
        names, cols = [], []
        for name in self.nominal:
            kind = self.spec[name].kind
            if fresh:
                col = self._nominal_column(name, z)
            elif regrid and kind in ("actuator_gain", "actuator_kv"):  # gains act through the effect
                col = self.idyn.regressor(z, name, _step_for(self.spec, name), ("act",))
            else:
                col = self.cols[name]
            names.append(name)
            cols.append(col)
        for name in cand.linear:
            names.append(name)
            cols.append(self.column(name))
        if cand.effect == "coulomb_friction":
            cc = self._coulomb_columns(cand.target, cand.two_sided)
            cols += cc
            names += ["+level", "-level"] if cand.two_sided else ["level"]
        lows, highs = [], []
        for name in names:
            if name in self.spec:
                i = self.spec.index(name)
                lows.append(self.spec.low[i] - z[i])
                highs.append(self.spec.high[i] - z[i])
            else:  # friction levels
                lows.append(0.0)
                highs.append(self.spec[f"coulomb:{cand.target}"].high)
        d, rt, rv, cov, n = self._solve(r0, cols, names, lows, highs)
        if cand.effect == "sensor_offset" and cand.linear:  # enters through sin/cos: one Gauss-Newton pass
            zz = z.copy()
            for nm, dv in zip(names, d):
                zz[self.spec.index(nm)] += dv
            name = cand.linear[0]
            col = self.idyn.regressor(zz, name, _step_for(self.spec, name))
            r1 = self.idyn.residual(zz)
            cols2 = [self.cols[nm] for nm in self.nominal] + [col]
            lows2 = [self.spec.low[self.spec.index(nm)] - zz[self.spec.index(nm)] for nm in names]
            highs2 = [self.spec.high[self.spec.index(nm)] - zz[self.spec.index(nm)] for nm in names]
            d2, rt, rv, cov, n = self._solve(r1, cols2, names, lows2, highs2)
            z, d = zz, d2
        zf = np.array(z, np.float32)
        params, std = {}, {}
        for k, (nm, dv) in enumerate(zip(names, d)):
            sd = float(np.sqrt(cov[k, k])) if np.isfinite(cov[k, k]) and cov[k, k] >= 0 else float("nan")
            if nm in self.spec:
                zf[self.spec.index(nm)] += dv
                params[nm], std[nm] = float(zf[self.spec.index(nm)]), sd
            else:
                params[nm], std[nm] = float(dv), sd
        if cand.effect == "coulomb_friction":
            self._set_coulomb(zf, cand, params, std, cov, names)
        if cand.grid_param:
            params[cand.grid_param] = float(z[self.spec.index(cand.grid_param)])
            std[cand.grid_param] = float("nan")
        return Fit(cand, zf, params, std, rt, rv, self._bic(rt, n, cand.num_params + len(self.nominal)))

    def _set_coulomb(self, zf, cand, params, std, cov, names):
        """Levels per direction -> the library's (Fc, asymmetry)."""
        j = cand.target
        if cand.two_sided:
            p, n = params.pop("+level"), params.pop("-level")
            sp, sn = std.pop("+level"), std.pop("-level")
            fc = (p + n) / 2
            asym = (p - n) / (p + n) if p + n > 0 else 0.0
            params[f"coulomb:{j}"], std[f"coulomb:{j}"] = fc, 0.5 * float(np.hypot(sp, sn))
            params[f"coulomb_asym:{j}"], std[f"coulomb_asym:{j}"] = asym, float(np.hypot(sp, sn) / max(p + n, 1e-9))
            zf[self.spec.index(f"coulomb_asym:{j}")] = np.clip(asym, -1, 1)
        else:
            fc = params.pop("level")
            params[f"coulomb:{j}"], std[f"coulomb:{j}"] = fc, std.pop("level")
        zf[self.spec.index(f"coulomb:{j}")] = fc


def rank(fits: list[Fit], min_gain: float = 0.02, min_bic_drop: float = 10.0, verify=None, top_k: int = 4,
         refine=None):
    """Order fits by BIC, then decide the selected one (``none`` unless an effect clearly wins).

    Screening by BIC on the equation error is cheap but noise-limited (it differentiates twice);
    so the ``top_k`` effects and ``none`` are verified by ``verify(fit) -> error`` (simulated
    predictions on held-back data, lower is better) and the best verified one is selected. An
    effect is named only if it passed the screen below and beats ``none`` by ``min_gain``
    (relative) in the verified error.

    ``refine(fit, err) -> (fit, err)`` (optional) improves a close contender by simulation.

    Returns ``(ordered fits, selected fit, confidence, weights, verified {label: error})``; the
    confidence is the BIC weight of the selection among all candidates, times its share of the
    verification weights ``exp(-n * log(err))`` normalised over the verified set when given.

    The screen: effects go to verification when they beat ``none`` by ``min_bic_drop`` in BIC, or beat it
    in BIC at all and by ``min_gain`` in held-out equation error (a saturation that acts on a
    few percent of the samples moves the BIC a lot but the held-out RMSE little; an effect
    worse than ``none`` by BIC is never named: a sub-sample delay, for one, improves 1 s
    predictions from noisy measured states even of the true model).
    """
    none = next(f for f in fits if f.candidate.effect == "none")
    ordered = sorted(fits, key=lambda f: f.bic)
    # one entry per effect@target (the better of e.g. symmetric / two-sided Coulomb)
    seen, uniq = set(), []
    for f in ordered:
        if f.candidate.label not in seen:
            seen.add(f.candidate.label)
            uniq.append(f)
    b = np.array([f.bic for f in uniq])
    w = np.exp(-(b - b.min()) / 2)
    w = w / w.sum()
    eligible = [f for f in uniq if f.candidate.effect != "none" and (
        f.bic < none.bic - min_bic_drop or (f.bic < none.bic and f.val_rmse < (1 - min_gain) * none.val_rmse))]
    verified = {}
    if verify is None:
        selected = eligible[0] if eligible else none
        conf = float(w[uniq.index(selected)])
        return uniq, selected, conf, w, verified
    pool, verified = [], {}
    for f in eligible[:top_k] + [none]:
        tried = [(float(verify(g)), g) for g in [f] + list(f.alternatives)]
        err, g = min(tried, key=lambda t: t[0])
        verified[f.candidate.label] = err
        if g is not f:  # a grid neighbour predicts better: it replaces the screened fit
            i = uniq.index(f)
            uniq[i] = g
        if f is not none:
            pool.append(g)
    if refine is not None and pool:
        # close contenders (within 2x of the best verified error) are refined by simulation
        # (output error), which removes the equation error's smoothing bias from all of them
        lead = min(verified.values())
        close = [f for f in pool + [none] if verified[f.candidate.label] <= 2.0 * lead]
        for k, f in enumerate(pool + [none] if len(close) > 1 else []):
            lab = f.candidate.label
            if verified[lab] <= 2.0 * lead:
                g, err = refine(f, verified[lab])
                if err < verified[lab]:
                    verified[lab] = err
                    uniq[[u.candidate.label for u in uniq].index(lab)] = g
                    if k < len(pool):
                        pool[k] = g
                    else:
                        none = g
    best = min(pool, key=lambda f: verified[f.candidate.label], default=None)
    if best is not None and verified[best.candidate.label] < (1 - min_gain) * verified[none.candidate.label]:
        selected = best
    else:
        selected = none
    errs = np.array(list(verified.values()))
    share = np.exp(-np.log(errs / errs.min()) * 20.0)  # 5% worse error -> weight e^-1
    share = share / share.sum()
    conf = float(share[list(verified).index(selected.candidate.label)])
    return uniq, selected, conf, w, verified


def ties(verified: dict[str, float], selected: str, tol: float) -> list[str]:
    """Effects the data cannot tell from the selected one: labels (other than ``selected`` and
    ``none``) whose verified error is within ``tol`` (relative) of the selected effect's.

    A 1.5-step action delay and a 2 ms motor lag in front of a slow servo, for one, predict the
    same motion to within the sensor noise; which of them comes first is then an accident of
    rounding, and the diagnosis says so instead of pretending to know.
    """
    is_none = lambda lab: lab.split("@")[0] == "none"
    if selected not in verified or is_none(selected):
        return []
    ref = verified[selected]
    return [lab for lab, err in sorted(verified.items(), key=lambda t: t[1])
            if lab != selected and not is_none(lab) and err <= (1 + tol) * ref]


def refine_by_simulation(fit: Fit, spec, verify, err0: float, max_evals: int = 80) -> tuple[Fit, float]:
    """Nelder-Mead on ``verify`` (simulated prediction error) over the fit's parameters.

    Parameters are scaled by their fitted magnitude (relative steps of 10%; additive steps for
    those fitted at zero); the grid parameter of delay / lag / saturation / backlash is freed
    too. Returns the better of the refined and the given fit, with its error.
    """
    from scipy.optimize import minimize

    names = [n for n in fit.params if n in spec]
    if not names:
        return fit, err0
    idx = np.array([spec.index(n) for n in names])
    x0 = np.asarray(fit.z, np.float64)[idx]
    scale = np.where(np.abs(x0) > 1e-9, np.abs(x0), 0.01 * (spec.high[idx] - spec.low[idx]))
    lo, hi = spec.low[idx].copy(), spec.high[idx].copy()
    c = fit.candidate
    if c.grid_param in names:  # the grid's span is the searched range (timing: >= one sample)
        k = names.index(c.grid_param)
        lo[k], hi[k] = max(lo[k], min(c.grid)), min(hi[k], max(c.grid))
    cache = {}

    def z_of(u):
        z = np.array(fit.z, np.float32)
        z[idx] = np.clip(x0 + u * scale, lo, hi)
        return z

    def f(u):
        key = tuple(np.round(u, 6))
        if key not in cache:
            zz = z_of(u)
            cache[key] = float(verify(dataclasses.replace(fit, z=zz)))
        return cache[key]

    simplex = np.vstack([np.zeros(len(idx)), 0.1 * np.eye(len(idx))])
    res = minimize(f, np.zeros(len(idx)), method="Nelder-Mead",
                   options={"initial_simplex": simplex, "maxfev": max_evals, "xatol": 1e-3, "fatol": 1e-4 * err0})
    if res.fun >= err0:
        return fit, err0
    z = z_of(res.x)
    params = dict(fit.params)
    for n, i in zip(names, idx):
        params[n] = float(z[i])
    return dataclasses.replace(fit, z=z, params=params, alternatives=[]), float(res.fun)
