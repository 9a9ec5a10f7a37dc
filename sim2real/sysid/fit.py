"""Fit physics parameters to multiple-shooting predictions: Gauss-Newton with per-segment velocities.

Objective over the chosen segments ``s`` (``shooting.py``)::

    Phi(theta, v) = sum_s |r_s(theta, v_s)|^2 + sum_s |(v_s - v_hat_s) / sigma_v_s|^2

``r_s``: the segment's prediction errors over each signal's noise scale; ``v_s``: its initial
velocity, a nuisance estimated with the parameters -- the data's own estimate ``v_hat_s``
(smoothed, or measured) is its prior, so a segment whose start velocity the noise blurred is not
blamed on the physics. Jacobians are finite differences from the batched simulator: one
simulation per parameter and one per velocity dimension (all segments move their velocity
together; each segment only sees its own). The velocities are eliminated segment by segment
(Schur complement), so a step costs a ``p x p`` solve however many segments there are.

Directions of the parameters the data cannot determine -- the common scale of every mass and
damping in a free swing with no known force, a damping on a joint that never moves -- have a
standard error larger than the parameter itself (in units of its scale); steps leave them where
they started (the nominal value) and ``Result.unidentified`` names them.

Why not gradients through MJX: finite differences over a batch of 8 reuse the one compiled
simulator (a reverse-mode pass through thousands of MJX steps costs a second, slow compile and
memory for every step), and a p x p Gauss-Newton solve needs only the Jacobian.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from sim2real._precision import real
from sim2real.sysid.shooting import B, Shooting


@dataclasses.dataclass
class Result:
    """A fitted model.

    Attributes:
      z: ``[P]`` physics vector; v0: ``[S, nv]`` initial velocities of every segment.
      names: the fitted parameters; std: their standard errors (same units).
      phi: objective on the fitted segments; sse: its data part; n: residual count.
      unidentified: combinations the data cannot determine, ``[{name: weight}]`` (held at start).
      iterations: Gauss-Newton iterations run.
      corr: ``[len(names), len(names)]`` correlation of the fitted parameters' estimates (NaN
        where a parameter is not identified); None when nothing was fitted.
    """

    z: np.ndarray
    v0: np.ndarray
    names: list
    std: dict
    phi: float
    sse: float
    n: int
    unidentified: list
    iterations: int
    corr: np.ndarray | None = None


class Fitter:
    """Gauss-Newton fits on the segments ``tiles`` of ``shooting``.

    Args:
      shooting: the batched simulator.
      scales: ``{name: typical magnitude}`` of every parameter that may be fitted (FD step 1% of
        it, step sizes and identifiability measured in its units).
      refine_iters: the class's default (below) unless given.
    """

    # Gauss-Newton steps of a judged model's start velocities (``velocities``): one did not
    # converge for a model whose prediction depends sharply on them (``DiagnoseConfig.refine_iters``)
    refine_iters: int = 3

    def __init__(self, shooting: Shooting, scales: dict[str, float], refine_iters: int | None = None):
        self.sh = shooting
        if refine_iters is not None:
            self.refine_iters = refine_iters
        self.spec = shooting.sys.spec
        self.scales = scales
        self.v_hat = shooting.v0.copy()
        self.sigma_v = shooting.sigma_v             # [S, nv]: each segment's start velocity prior
        # finite-difference step of the velocities (one per dof, all segments together)
        self.dv = np.maximum(np.median(self.sigma_v, 0), 1e-4 * (np.abs(self.v_hat).max(0) + 1e-3))
        self.nv = shooting.v0.shape[1]

    def narrow_velocity_steps(self) -> None:
        """At most 5% of the typical speed as the velocities' finite-difference step: where the
        data's estimates are poor (rough motion) their prior is wide, and a step that wide would
        measure a secant of the motion, not its slope."""
        rms = np.sqrt(np.mean(self.v_hat**2, 0))
        self.dv = np.maximum(np.minimum(self.dv, 0.05 * rms + 1e-12), 1e-4 * (np.abs(self.v_hat).max(0) + 1e-3))

    # ------------------------------------------------------------------------------------------
    def residuals(self, zs, v0s, tiles) -> np.ndarray:
        """``[b, k, m]`` for any number ``b`` of physics (batched by 8)."""
        out = []
        for c in range(0, len(zs), B):
            p = self.sh.predict(np.asarray(zs[c:c + B]), np.asarray(v0s[c:c + B]), tiles)
            out.append(self.sh.residuals(p, tiles))
        return np.concatenate(out)

    def prior(self, v0, tiles) -> float:
        return float(np.sum(((v0[tiles] - self.v_hat[tiles]) / self.sigma_v[tiles]) ** 2))

    def phi(self, r, v0, tiles) -> float:
        return float(np.sum(r**2)) + self.prior(v0, tiles)

    def _steps(self, z, names):
        idx = self.spec.indices(names)
        step = np.array([0.01 * self.scales[n] for n in names])
        up = z[idx] + step <= self.spec.high[idx]
        return idx, np.where(up, step, -step)

    def jacobian(self, z, v0, names, tiles, r0=None):
        """``(r0 [k, m], J_theta [k, m, p] per unit of scale, J_v [k, m, nv])``."""
        idx, step = self._steps(z, names)
        dv = self.dv
        zs, vs = [], []
        if r0 is None:
            zs.append(z)
            vs.append(v0)
        for i, st in zip(idx, step):
            zz = z.copy()
            zz[i] += st
            zs.append(zz)
            vs.append(v0)
        for k in range(self.nv):
            vv = v0.copy()
            vv[:, k] += dv[k]
            zs.append(z)
            vs.append(vv)
        r = self.residuals(np.stack(zs), np.stack(vs), tiles)
        if r0 is None:
            r0, r = r[0], r[1:]
        p = len(names)
        scale = np.array([self.scales[n] for n in names])
        J_t = np.stack([(r[i] - r0) / step[i] * scale[i] for i in range(p)], -1) if p else np.zeros(r0.shape + (0,))
        J_v = np.stack([(r[p + k] - r0) / dv[k] for k in range(self.nv)], -1)
        return r0, J_t, J_v

    # ------------------------------------------------------------------------------------------
    def _reduce(self, r0, J_t, J_v, v0, tiles):
        """Eliminate the segment velocities: ``(H [p, p], g [p], solve_v, v_gain)`` of the reduced
        system; ``v_gain``: how much the objective drops (linearised) when only the velocities move."""
        lam = 1.0 / self.sigma_v[tiles] ** 2                        # [k, nv]
        dv_prior = (v0[tiles] - self.v_hat[tiles]) * lam          # [k, nv]
        # (batched matmuls, not einsum: numpy's einsum runs the three-operand products and the
        # sums over k and m in its own loops, not BLAS; this was a tenth of a 3-link arm's case)
        Jvt = J_v.transpose(0, 2, 1)
        A = Jvt @ J_v + lam[:, :, None] * np.eye(self.nv)[None]   # [k, nv, nv]
        b = (Jvt @ r0[..., None])[..., 0] + dv_prior              # [k, nv]
        C = J_t.transpose(0, 2, 1) @ J_v                           # [k, p, nv]
        Ainv = np.linalg.inv(A)
        CA = C @ Ainv                                              # [k, p, nv]
        Jt = J_t.reshape(-1, J_t.shape[-1])
        H = Jt.T @ Jt - np.einsum("kpj,kqj->pq", CA, C)
        g = Jt.T @ r0.reshape(-1) - np.einsum("kpj,kj->p", CA, b)

        def solve_v(du):
            return -(Ainv @ (b + du @ C)[..., None])[..., 0]

        return H, g, solve_v, float(np.sum(b * (Ainv @ b[..., None])[..., 0]))

    @staticmethod
    def _identifiable(H, sigma2):
        """Eigen-directions of ``H`` whose standard error is below one unit of scale."""
        w, V = np.linalg.eigh(0.5 * (H + H.T))
        keep = w > max(sigma2, 1e-12) * 1.0
        return w, V, keep

    def range_of(self, names, bounds=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(indices, lo, hi)`` of parameters ``names``: their physical bounds, narrowed to
        ``bounds`` (``{name: (lo, hi)}``) where given; what ``fit`` keeps every step inside."""
        idx = self.spec.indices(names) if names else np.zeros(0, int)
        lo, hi = self.spec.low[idx].astype(float), self.spec.high[idx].astype(float)
        for k, n in enumerate(names):
            if bounds and n in bounds:
                lo[k], hi[k] = max(lo[k], bounds[n][0]), min(hi[k], bounds[n][1])
        return idx, lo, hi

    def fit(self, z0, v0, names, tiles, iters: int = 6, tol: float = 1e-3, bounds=None, at_noise: bool = False) -> Result:
        """Gauss-Newton / Levenberg-Marquardt from ``z0``; ``bounds``: ``{name: (lo, hi)}``
        narrower than the physical ones (a search range).

        ``at_noise``: the steps leave put only the directions the data's *noise* leaves undetermined
        (the residual variance taken as at most its noise level, 1 per residual, times the
        correlation's inflation), not those the current misfit does. The standard errors are the
        misfit's either way. A start far from the fit misfits by orders of magnitude more than the
        noise, and measured against that misfit every direction but the steepest is "unidentified":
        the fit never leaves its start (the combos list's 6127: a 0.05 rad sensor offset beside a
        joint spring, fitted from its grid point 0.02 and left there, training objective 1.4e5
        against 13 at the truth; ``tuning.md`` step 77)."""
        z = np.asarray(z0, real()).copy()
        v0 = np.asarray(v0, float).copy()
        idx, lo, hi = self.range_of(names, bounds)
        scale = np.array([self.scales[n] for n in names])
        # a start outside the range is brought inside first: every step is clipped into it, so a
        # fit that started outside had every step rejected and stayed there (the IBM double
        # pendulum's payloads, scaled 25x with the masses by ``Selector._at_model_masses``, sat
        # at 4-5x their range's top whatever the data said)
        z[idx] = np.clip(z[idx], lo, hi)
        r0 = self.residuals(z[None], v0[None], tiles)[0]
        phi = self.phi(r0, v0, tiles)

        def held_below(sigma2, inflation):
            """The variance under which a direction's curvature leaves it put (``at_noise``: the
            noise's, 1 per residual times the correlation's ``inflation``)."""
            return min(sigma2, inflation) if at_noise else sigma2
        mu = 1e-3
        it = 0
        H = np.zeros((len(names), len(names)))
        keep = np.zeros(len(names), bool)
        V = np.eye(len(names))
        sigma2 = 1.0
        age = None  # iterations since the Jacobian was computed
        here = False  # the Jacobian is the current point's (no step taken since it was computed)
        for it in range(1, iters + 1):
            if age is None or age >= 2:
                # (a Jacobian serves two steps: the second reuses it at the new point, a chord step)
                r0, J_t, J_v = self.jacobian(z, v0, names, tiles, r0)
                age, here = 0, True
            else:
                # the residual moved; the linear model around the old point is shifted to the new one
                pass
            age += 1
            H, g, solve_v, _ = self._reduce(r0, J_t, J_v, v0, tiles)
            n = r0.size
            inflation = self._correlation(r0)
            sigma2 = max(phi / max(n - len(names), 1), 1e-12) * inflation
            w, V, keep = self._identifiable(H, held_below(sigma2, inflation))
            trials = []
            for m in (mu * 0.1, mu, mu * 10.0):
                # Levenberg-Marquardt in the identifiable subspace (the others stay put)
                gv = V.T @ g
                d = np.where(keep, -gv / np.maximum(w + m * np.maximum(w, 1e-12), 1e-300), 0.0)
                du = V @ d
                for frac in (1.0, 0.4):
                    th = np.clip(z[idx] + frac * du * scale, lo, hi)
                    du_eff = (th - z[idx]) / scale
                    zz = z.copy()
                    zz[idx] = th
                    vv = v0.copy()
                    vv[tiles] = v0[tiles] + solve_v(du_eff)
                    trials.append((m, zz, vv))
            trials = trials[: B - 1] + [(mu, z, self._velocity_only(v0, solve_v, len(names), tiles))]
            rs = self.residuals(np.stack([t[1] for t in trials]), np.stack([t[2] for t in trials]), tiles)
            phis = [self.phi(rs[i], trials[i][2], tiles) for i in range(len(trials))]
            best = int(np.argmin(phis))
            if not phis[best] < phi:
                mu *= 10.0
                if mu > 1e6:
                    break
                # a rejected step: a fresh Jacobian, unless the one in hand is this point's already
                # (computing it again gave the same numbers: 40 of a 3-link arm's 402 calls)
                age = 0 if here else None
                continue
            gain = (phi - phis[best]) / max(phi, 1e-300)
            # where only the velocities' step helped, the parameters' steps were too long: the next
            # are shorter (a quadrotor's payload fitted from 4x its moment had every step rejected
            # for the velocities' and its damping cut each time, and never left its start)
            mu = mu * 10.0 if best == len(trials) - 1 else max(trials[best][0] * 0.3, 1e-6)
            z, v0, r0, phi = trials[best][1], trials[best][2], rs[best], phis[best]
            here = False
            if gain < tol:
                break
        # (the directions the steps left put are those reported; the errors are the misfit's)
        std, unidentified, corr = self._errors(H, sigma2, held_below(sigma2, self._correlation(r0)), names, scale)
        return Result(z, v0, list(names), std, phi, float(np.sum(r0**2)), int(r0.size), unidentified, it, corr)

    def _errors(self, H, sigma2, held, names, scale):
        """``(std, unidentified, corr)`` in parameter units from the reduced Gauss-Newton matrix ``H``
        (``sigma2``: the residual variance; ``held``: the one under which a direction is undetermined)."""
        std, unidentified, corr = {}, [], None
        if len(names):
            w, V, keep = self._identifiable(H, held)
            winv = np.where(keep, 1.0 / np.maximum(w, 1e-300), 0.0)
            cov = (V * winv) @ V.T * sigma2
            for k, nm in enumerate(names):
                std[nm] = float(np.sqrt(max(cov[k, k], 0.0)) * scale[k]) if keep.any() else float("nan")
            sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
            with np.errstate(invalid="ignore", divide="ignore"):
                corr = np.where(np.outer(sd, sd) > 0, cov / np.outer(sd, sd), np.nan)
            for i in np.where(~keep)[0]:
                vec = V[:, i]
                big = np.argsort(-np.abs(vec))[:4]
                unidentified.append({names[j]: round(float(vec[j]), 3) for j in big if abs(vec[j]) > 0.2})
        return std, unidentified, corr

    def errors(self, z, v0, names, tiles):
        """``(std, unidentified)`` of ``names`` at ``z``, the other parameters held (no step taken):
        a free swing's effects with its masses held at the model's (``diagnose.at_nominal_masses``)."""
        names = list(names)
        scale = np.array([self.scales[n] for n in names])
        r0, J_t, J_v = self.jacobian(np.asarray(z, real()), np.asarray(v0, float), names, tiles)
        H = self._reduce(r0, J_t, J_v, v0, tiles)[0]
        sigma2 = max(self.phi(r0, v0, tiles) / max(r0.size - len(names), 1), 1e-12) * self._correlation(r0)
        std, unidentified, _ = self._errors(H, sigma2, sigma2, names, scale)
        return std, unidentified

    def _velocity_only(self, v0, solve_v, p, tiles):
        vv = v0.copy()
        vv[tiles] = v0[tiles] + solve_v(np.zeros(p))
        return vv

    @staticmethod
    def _correlation(r):
        """Variance inflation for residuals correlated along each segment: (1 + rho) / (1 - rho)
        of their lag-1 autocorrelation (prediction errors are smooth within a segment)."""
        a, b = r[:, :-1].ravel(), r[:, 1:].ravel()
        denom = np.sqrt(np.sum(a * a) * np.sum(b * b))
        rho = float(np.clip(np.sum(a * b) / denom, 0.0, 0.98)) if denom > 0 else 0.0
        return (1 + rho) / (1 - rho)

    def velocities(self, z, v0, tiles, iters: int | None = None):
        """Refine only the segments' initial velocities (parameters fixed); returns
        ``(v0, per-segment objective [k])`` -- how well ``z`` predicts each segment."""
        return self.velocities_many([z], [v0], tiles, iters)[0]

    def velocities_many(self, zs, v0s, tiles, iters: int | None = None):
        """:meth:`velocities` for several models, their simulations batched together (``iters``:
        ``refine_iters`` unless given)."""
        iters = self.refine_iters if iters is None else iters
        M = len(zs)
        zs = [np.asarray(z, real()) for z in zs]
        v0s = [np.asarray(v, float).copy() for v in v0s]
        dv = self.dv
        lam = 1.0 / self.sigma_v[tiles] ** 2

        def obj(r, v):
            return np.sum(r**2, 1) + np.sum(((v[tiles] - self.v_hat[tiles]) / self.sigma_v[tiles]) ** 2, 1)

        r0 = list(self.residuals(np.stack(zs), np.stack(v0s), tiles))
        # Levenberg damping per segment: 0 until a step fails to lower its objective (so one
        # iteration is plain Gauss-Newton), then raised tenfold per failure, eased on success
        mu = [np.zeros(len(tiles)) for _ in range(M)]
        for _ in range(iters):
            batch_z, batch_v = [], []
            for i in range(M):
                for k in range(self.nv):
                    vv = v0s[i].copy()
                    vv[:, k] += dv[k]
                    batch_z.append(zs[i])
                    batch_v.append(vv)
            rk = self.residuals(np.stack(batch_z), np.stack(batch_v), tiles)
            trial = []
            for i in range(M):
                J_v = np.stack([(rk[i * self.nv + k] - r0[i]) / dv[k] for k in range(self.nv)], -1)
                JJ = np.einsum("kmi,kmj->kij", J_v, J_v)
                A = JJ + (lam + mu[i][:, None] * np.einsum("kii->ki", JJ))[:, :, None] * np.eye(self.nv)[None]
                b = np.einsum("kmi,km->ki", J_v, r0[i]) + (v0s[i][tiles] - self.v_hat[tiles]) * lam
                vv = v0s[i].copy()
                vv[tiles] = v0s[i][tiles] - np.linalg.solve(A, b[..., None])[..., 0]
                trial.append(vv)
            r1 = self.residuals(np.stack(zs), np.stack(trial), tiles)
            for i in range(M):
                better = obj(r1[i], trial[i]) < obj(r0[i], v0s[i])
                mu[i] = np.where(better, mu[i] / 3, np.maximum(10 * mu[i], 1e-3))
                v0s[i][tiles[better]] = trial[i][tiles[better]]
                r0[i] = np.where(better[:, None], r1[i], r0[i])
        return [(v0s[i], obj(r0[i], v0s[i])) for i in range(M)]
