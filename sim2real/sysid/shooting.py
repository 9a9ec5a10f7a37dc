"""Batched multiple-shooting predictions: every segment of every recording, for 8 physics at once.

Each recording is cut into consecutive segments of ``H`` samples. A segment starts from the
measured positions and an initial velocity (the data's estimate, refined per segment by the
fits) and is simulated through the recorded commands; its prediction of the next ``H`` samples
is compared with the measurements. Segments stay meaningful where a whole-recording replay
drifts (unstable or chaotic systems), and their errors are nearly independent of each other.

The command path (delay line, motor lag, backlash gap, MuJoCo's own actuator activations) has
memory longer than a segment, so its state at every segment start comes from running it over
each recording from its start (``_command_states``: no physics, one scan), which begins at
rest under the recording's first command; the segments themselves are simulated in parallel. One jitted function serves every call of a diagnosis:
``predict(zs [8, P], v0 [8, S, nv], tiles [Sc])`` -- the batch of 8 physics vectors is a fixed
shape, as is the number of segments per call, so it compiles once per model and sample rate.

Initial activations: an integrating servo (``intvelocity``) starts at the joint's measured
position, a filter at the first command (the system at rest); the diagnosis says so.
"""
from __future__ import annotations

import dataclasses
import time

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from jax.sharding import PartitionSpec as P

from sim2real._precision import real
from sim2real.envs import parallel
from sim2real.physics import stepper
from sim2real.physics.params import clip
from sim2real.sysid import native
from sim2real.sysid.derivatives import velocity_state
from sim2real.sysid.trajectory import SPREAD_FLOOR, kink_error, moves, signal_scale, start_velocity

B = 8  # physics vectors per call


@dataclasses.dataclass
class Tiles:
    """Segments of all recordings (consecutive within each recording).

    Attributes:
      start: ``[S]`` global index of each segment's first sample (recordings concatenated);
        local: ``[S]`` the same sample's index within its own recording.
      traj: ``[S]`` which trajectory; first: ``[S]`` bool, first segment of its recording.
      label: ``[S]`` "fit" | "val" | "heldout" | "" (a segment straddling the fit/val boundary) |
        "edge" (starting within half a smoothing window of the recording's start).
    """

    start: np.ndarray
    traj: np.ndarray
    first: np.ndarray
    label: np.ndarray
    local: np.ndarray

    def of(self, label: str) -> np.ndarray:
        return np.where(self.label == label)[0]


class Shooting:
    """Multiple-shooting predictor for ``system`` over ``trajs`` with segments of ``horizon`` samples.

    Args:
      system: ``sysid.system.System`` (its timestep already set to the sample period's sub-step).
      trajs: trajectories, all at one sample period.
      heldout: indices of ``trajs`` that are held out (their segments are labelled "heldout").
      val_fraction: tail of every other trajectory whose segments are labelled "val".
      floor: each signal's weight is ``1 / (noise^2 + (floor * its std)^2)``: a signal
        measured with almost no noise still does not outweigh every other one.
      budget: physics steps per physics vector that one call of the fit segments may cost; when
        the recordings hold more, evenly spaced segments are used (validation and held-out sets:
        2/3 of it). What a diagnosis costs then depends on the model, not on the recordings' length.
    """

    def __init__(self, system, trajs, horizon: int, heldout=(), val_fraction: float = 0.3,
                 floor: float = SPREAD_FLOOR, batch: int = B, budget: int = 6000):
        self.sys, self.trajs, self.H = system, trajs, int(horizon)
        self.B = int(batch)
        m = system.mj
        self.dt = trajs[0].dt
        self.n = system.substeps
        H = self.H
        starts, local, traj, first, label, offset = [], [], [], [], [], 0
        for r, tr in enumerate(trajs):
            T = len(tr)
            boundary = int(T * (1 - val_fraction))
            for k, s in enumerate(range(0, T - H, H)):
                starts.append(offset + s)
                local.append(s)
                traj.append(r)
                first.append(k == 0)
                if s < tr.window // 2 + 1:
                    # the smoothing window reaches past the recording's start: its velocity is an
                    # extrapolation, not an estimate (the command path still runs from sample 0)
                    label.append("edge")
                elif r in heldout:
                    label.append("heldout")
                elif s + H <= boundary:
                    label.append("fit")
                elif s >= boundary:
                    label.append("val")
                else:
                    label.append("")
            offset += T
        if not starts:
            raise ValueError(f"recordings shorter than one prediction horizon ({H} samples)")
        label = np.array(label, dtype=object)
        per_tile = H * system.substeps
        for name, share in (("fit", 1.0), ("val", 2 / 3), ("heldout", 2 / 3)):
            idx = np.where(label == name)[0]
            cap = max(4, int(budget * share // per_tile))
            if len(idx) > cap:  # keep evenly spaced segments, mark the rest unused
                keep = idx[np.round(np.linspace(0, len(idx) - 1, cap)).astype(int)]
                label[np.setdiff1d(idx, keep)] = name + "-unused"
        self.tiles = Tiles(np.array(starts), np.array(traj), np.array(first), label.astype(str), np.array(local))
        S = len(starts)
        self.Sc = max(len(self.tiles.of(x)) for x in ("fit", "val", "heldout"))
        cat = lambda f: np.concatenate([f(tr) for tr in trajs])  # noqa: E731
        q_all = cat(lambda tr: tr.q)
        self.q_all = q_all
        # measured targets of every segment: samples start+1 .. start+H
        idx = self.tiles.start[:, None] + 1 + np.arange(H)[None]
        self.signals = {"qpos": q_all[idx]}
        # each signal's noise std, the largest of the recordings' (``[n]`` per kind), and its scale
        self.noise = {"qpos": np.max([tr.sigma_q for tr in trajs], 0)}
        scale = {"qpos": signal_scale([self.noise["qpos"]], q_all, floor, system.angles)}
        # the measured velocity columns compared (None: the recordings have none) and those left out
        self.qvel_cols, self.left_out = None, []
        if all(tr.qvel is not None for tr in trajs):
            qv = cat(lambda tr: tr.qvel)
            # a measured velocity whose noise is as large as what it measures (an encoder's count
            # differenced at a fast rate) tells little about the motion, and weighted in, it adds
            # about one per residual to every model (``moves``): it is not compared.
            noise = np.max([tr.sigma_qvel for tr in trajs], 0)
            keep = moves(noise, np.std(qv, 0))
            self.left_out = [f"qvel:{system.dof_names[k]}" for k in np.where(~keep)[0]]
            self.qvel_cols = np.where(keep)[0]
            if keep.any():
                self.signals["qvel"] = qv[idx][..., keep]
                self.noise["qvel"] = noise[keep]
                scale["qvel"] = signal_scale([self.noise["qvel"]], qv[:, keep], floor)
        if m.nu and all(tr.force is not None for tr in trajs):
            fo = cat(lambda tr: tr.force)
            self.signals["force"] = fo[idx]
            self.noise["force"] = np.max([tr.sigma_force for tr in trajs], 0)
            scale["force"] = signal_scale([self.noise["force"]], fo, floor)
        self.scale = {k: np.maximum(v, 1e-12) for k, v in scale.items()}
        # the measured state at every segment start
        st = self.tiles.start
        self.q0 = q_all[st]
        # (a start within a command step's window: ``start_velocity``; where its kink could not be
        # refitted, how far it can bend the estimate: ``kink_error``)
        self.v0, kink = np.empty((S, m.nv)), np.empty((S, m.nv))
        for r, tr in enumerate(trajs):
            sel = self.tiles.traj == r
            v_st, a_st, opened = start_velocity(tr, self.tiles.local[sel])
            self.v0[sel] = velocity_state(v_st, a_st, system.h)
            kink[sel] = kink_error(tr, self.tiles.local[sel], opened, self.v0[sel], system.mj)
        # each segment's start velocity is trusted as far as the data there allows (``sigma_v_t``),
        # and no further than a command's kink can bend it where that was not refitted
        local = np.stack([trajs[r].sigma_v_t[s] if trajs[r].sigma_v_t is not None else trajs[r].sigma_v
                          for s, r in zip(self.tiles.local, self.tiles.traj)])
        self.sigma_v = np.hypot(local * 1.5, kink) + 1e-9 * (np.abs(self.v0).max(0) + 1)   # [S, nv]
        # inputs of the jitted function (device arrays, passed as arguments, not baked in)
        act0 = np.zeros((len(trajs), m.na))
        dact = np.zeros((len(trajs), m.na, m.nq))
        for r, tr in enumerate(trajs):
            act0[r], dact[r] = self._initial_activation(tr)
        self._data = dict(
            ctrl=jnp.asarray(cat(lambda tr: tr.ctrl), real()),
            qfrc=jnp.asarray(cat(lambda tr: tr.qfrc), real()),
            q=jnp.asarray(q_all, real()), v=jnp.asarray(cat(lambda tr: tr.v), real()),
            start=jnp.asarray(st, jnp.int32), first=jnp.asarray(self.tiles.first),
            act0=jnp.asarray(act0[self.tiles.traj], real()), q0=jnp.asarray(self.q0, real()),
            dact=jnp.asarray(dact[self.tiles.traj], real()))
        # the command path's pre-run: recordings are independent (each starts at rest), so they run
        # side by side, each scanning its own segments in order (``order [R, Smax]``, padded with
        # its last segment); ``flat [S]`` finds segment s in the [R * Smax] result
        R = len(trajs)
        per = [np.where(self.tiles.traj == r)[0] for r in range(R)]
        smax = max(len(p) for p in per)
        order = np.stack([np.concatenate([p, np.full(smax - len(p), p[-1])]) for p in per])
        flat = np.empty(S, np.int64)
        for r, p in enumerate(per):
            flat[p] = r * smax + np.arange(len(p))
        self._data["order"] = jnp.asarray(order, jnp.int32)
        self._data["flat"] = jnp.asarray(flat, jnp.int32)
        self._fn, self._data = self._over_devices(self._predict_batch, self._data)
        self.calls = 0
        self.seconds = 0.0
        self.S = S

    # ------------------------------------------------------------------------------------------
    def _over_devices(self, fn, data):
        """``fn`` jitted, its physics vectors split over this process's devices where several divide
        ``B`` (``envs.parallel``: the diagnose command asks for one CPU device per core, as XLA runs
        one device's program on about one core); the recordings are copied to every device once."""
        mapped = parallel.env_slices(fn, self.B, in_specs=(parallel.ENVS, parallel.ENVS, P(), P()))
        if mapped is fn:
            return jax.jit(fn), data
        mesh = parallel.batch_sharding(self.B).mesh
        return jax.jit(mapped), jax.device_put(data, jax.sharding.NamedSharding(mesh, P()))

    def _initial_activation(self, tr) -> tuple[np.ndarray, np.ndarray]:
        """A recording's activations at its first sample ``[na]``, and how they move with the
        joints' positions there ``[na, nq]`` (``native.activation_at``; ``_command_states``)."""
        return native.activation_at(self.sys.mj, self.sys.columns, tr.q[0], tr.ctrl[0])

    def _act_step(self, act, u, h):
        """MuJoCo's activation dynamics for one step of length ``h`` (Euler; exact for filterexact)."""
        m = self.sys.mj
        out = act
        for a in range(m.nu):
            adr = int(m.actuator_actadr[a])
            if adr < 0:
                continue
            dyn, tau = int(m.actuator_dyntype[a]), float(m.actuator_dynprm[a, 0])
            x = act[adr]
            if dyn == int(mujoco.mjtDyn.mjDYN_INTEGRATOR):
                x = x + h * u[a]
            elif dyn == int(mujoco.mjtDyn.mjDYN_FILTEREXACT):
                x = x + (u[a] - x) * (1 - np.exp(-h / max(tau, 1e-9)))
            else:  # mjDYN_FILTER
                x = x + h * (u[a] - x) / max(tau, 1e-9)
            if m.actuator_actlimited[a]:
                x = jnp.clip(x, m.actuator_actrange[a, 0], m.actuator_actrange[a, 1])
            out = out.at[adr].set(x)
        return out

    def _command_states(self, z, data, skip=()):
        """Effect state and activations at every segment start ``([S] pytree, [S, na])``; ``skip``:
        stages off for every physics of the batch (``Effects.actuate``)."""
        sys, n, H = self.sys, self.n, self.H
        fx = sys.effects
        h = sys.h
        es_init = fx.init_state()

        def segment(carry, s):
            es, act = carry
            # a recording starts with its command path at rest under its first command
            rest = fx.steady_state(data["ctrl"][data["start"][s]])
            es = jax.tree_util.tree_map(lambda a, b: jnp.where(data["first"][s], b, a), es, rest)
            # an integrating servo's setpoint starts where the joint is, and a hypothesised sensor
            # offset moves where that is: at the measured position less the offset, not at the
            # measured one (there the servo would start pulling by the offset; the beside list's
            # 3847: a 0.02 rad offset screened at -1309 and was never fitted)
            q_first = data["q"][data["start"][s]]
            act0 = data["act0"][s] + data["dact"][s] @ (fx.unsense(z, q_first) - q_first)
            act = jnp.where(data["first"][s], act0, act)
            out = (es, act)

            def sample(c, k):
                es, act = c
                t = data["start"][s] + k
                es = fx.push(es, data["ctrl"][t])
                qt = fx.unsense(z, data["q"][t])
                vt = data["v"][t]

                def sub(c2, j):
                    es, act = c2
                    u, es = fx.actuate(z, es, j, n, qt, h, vt, act, skip=skip)
                    return (es, self._act_step(fx.activation(es, act), u, h)), None

                return jax.lax.scan(sub, (es, act), jnp.arange(n))[0], None

            return jax.lax.scan(sample, (es, act), jnp.arange(H))[0], out

        init = (es_init, jnp.zeros(sys.mj.na))
        per_rec = jax.vmap(lambda order: jax.lax.scan(segment, init, order)[1])(data["order"])   # [R, Smax]
        return jax.tree_util.tree_map(lambda x: x.reshape((x.shape[0] * x.shape[1],) + x.shape[2:])[data["flat"]], per_rec)

    def _segment(self, z, data, q0, v0, es, act, s, d0):
        """One segment of ``H`` samples under physics ``z [P]`` from positions ``q0 [nq]`` and velocities
        ``v0 [nv]``; ``d0`` is this segment's own copy of the template data (``_segments`` says why)."""
        sys = self.sys
        fx = sys.effects
        model = sys.physics.apply(z)
        d = d0.replace(qpos=fx.unsense(z, q0), qvel=v0)
        if sys.mj.na:
            d = d.replace(act=act)
        start = data["start"][s]
        # the command path was replayed with the estimated velocities; the segment starts from
        # refined ones, and what the joint dragged along (a backlash's motor side) moves with it
        es = fx.rebase(es, v0 - data["v"][start])
        u = jax.lax.dynamic_slice_in_dim(data["ctrl"], start, self.H)
        f = jax.lax.dynamic_slice_in_dim(data["qfrc"], start, self.H)

        def step(carry, x):
            d, es, alive = carry
            uk, fk = x
            d2, es2 = stepper.advance(fx, model, z, d, es, uk, self.dt, self.n, fk)
            ok = alive & jnp.isfinite(d2.qpos).all() & jnp.isfinite(d2.qvel).all() & (jnp.abs(d2.qvel) < 1e6).all()
            d2 = jax.tree_util.tree_map(lambda a, b: jnp.where(ok, a, b), d2, d)
            out = {"qpos": fx.measure(z, d2.qpos), "qvel": d2.qvel, "force": d2.actuator_force, "ok": ok}
            return (d2, es2, ok), out

        alive = jnp.isfinite(q0).all()   # (from the segment's own data, so batched from the start too)
        return jax.lax.scan(step, (d, es, alive), (u, f))[1]

    def _predict_batch(self, zs, v0, tiles, data):
        sys = self.sys
        fx = sys.effects
        zs = jax.vmap(lambda z: clip(sys.spec, z))(zs)
        rows = [int(r) for r in fx.command_rows]
        # the command path's memory matters only when some physics in the batch has a delay, lag or
        # backlash (or the model has activations); otherwise its states are the initial ones
        needed = jnp.any(zs[:, np.array(rows, np.int32)] > 0) if rows else jnp.zeros((), bool)
        if sys.mj.na:
            needed = jnp.ones((), bool)

        # a costly stage off for every physics of the batch (a backlash) is left out of the replay:
        # its state stays as it started, which no prediction reads while the stage is off. (One
        # branch for the batch, not one per step: a branch per sub-step cost as much as the sums.)
        skip = fx.skippable
        skip_off = jnp.all(jnp.concatenate([zs[:, fx.stage_rows[s]] <= 0 for s in skip], 1)) if skip else None

        def replay(left_out):
            return jax.vmap(lambda z: self._command_states(z, data, left_out))(zs)

        def run(_):
            return jax.lax.cond(skip_off, lambda: replay(skip), lambda: replay(())) if skip else replay(())

        def rest(_):  # no delay, lag or backlash anywhere: the state is the command itself (no memory)
            es = jax.vmap(lambda s: fx.steady_state(data["ctrl"][data["start"][s]]))(jnp.arange(self.S))
            es = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x, (zs.shape[0],) + x.shape), es)
            return es, jnp.zeros((zs.shape[0], self.S, sys.mj.na))

        es_all, act_all = jax.lax.cond(needed, run, rest, None)
        return self._segments(zs, v0, tiles, data, es_all, act_all)

    def _segments(self, zs, v0, tiles, data, es_all, act_all):
        """Segments ``tiles [k]`` under physics ``zs [B, P]`` from velocities ``v0 [B, S, nv]`` and
        command-path states ``es_all`` / ``act_all`` (``[B, S, ...]``); arrays ``[B, k, H, .]``."""
        # One vmap over every (physics, segment) pair, each with its own copy of the template data,
        # costs a third of the tracing of a vmap over physics around a vmap over segments: JAX
        # batches a scan's body once per vmap level, and again each time a carry that entered
        # unbatched (the shared template's fields) comes out batched, so MuJoCo's step was traced
        # 4-6 times over (5.3 -> 1.8 s per compile on a 3-link arm). The numbers are the same to
        # float rounding (the order of XLA's batched operations is not fixed).
        B, k = zs.shape[0], tiles.shape[0]
        flat = lambda x: x.reshape((B * k,) + x.shape[2:])  # noqa: E731
        pairs = lambda x: flat(jnp.broadcast_to(x[None], (B,) + x.shape))  # noqa: E731  (same for every physics)
        d0 = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x, (B * k,) + x.shape), self.sys.data0)
        out = jax.vmap(lambda z, q0, v, es, act, s, d: self._segment(z, data, q0, v, es, act, s, d))(
            flat(jnp.broadcast_to(zs[:, None], (B, k) + zs.shape[1:])), pairs(data["q0"][tiles]),
            flat(v0[:, tiles]), jax.tree_util.tree_map(lambda x: flat(x[:, tiles]), es_all),
            flat(act_all[:, tiles]), pairs(tiles), d0)
        return jax.tree_util.tree_map(lambda x: x.reshape((B, k) + x.shape[1:]), out)

    # ------------------------------------------------------------------------------------------
    def predict(self, zs: np.ndarray, v0: np.ndarray, tiles: np.ndarray) -> dict[str, np.ndarray]:
        """Predictions for ``zs [b, P]`` (b <= 8), initial velocities ``v0 [b, S, nv]``, segments
        ``tiles [k]``; returns arrays ``[b, k, H, .]`` (``ok [b, k, H]``)."""
        b, k = len(zs), len(tiles)
        if b > self.B:
            raise ValueError(f"at most {self.B} physics per call")
        zpad = np.concatenate([zs, np.repeat(zs[:1], self.B - b, 0)]).astype(real())
        vpad = np.concatenate([v0, np.repeat(v0[:1], self.B - b, 0)]).astype(real())
        out = {}
        t0 = time.perf_counter()
        for c0 in range(0, k, self.Sc):
            t = np.asarray(tiles[c0: c0 + self.Sc])
            tpad = np.concatenate([t, np.full(self.Sc - len(t), t[0])]).astype(np.int32)
            res = self._fn(jnp.asarray(zpad), jnp.asarray(vpad), jnp.asarray(tpad), self._data)
            self.calls += 1
            for key, val in res.items():
                out.setdefault(key, []).append(np.asarray(val)[:b, : len(t)])
        self.seconds += time.perf_counter() - t0
        out = {key: np.concatenate(v, axis=1) for key, v in out.items()}
        if self.qvel_cols is not None:  # only the measured columns compared
            out["qvel"] = out["qvel"][..., self.qvel_cols]
        return out

    def residuals(self, pred: dict, tiles: np.ndarray) -> np.ndarray:
        """Weighted residuals ``[b, k, H * n_signals]`` (prediction minus measurement over the
        signal's noise scale); a diverged step counts as 1e3 per element."""
        parts = []
        for key, meas in self.signals.items():
            e = (pred[key] - meas[tiles][None]) / self.scale[key]
            parts.append(e.reshape(e.shape[:3] + (-1,)))
        r = np.concatenate(parts, -1)
        bad = ~pred["ok"][..., None] | ~np.isfinite(r)
        r = np.where(bad, 1e3, r)
        return r.reshape(r.shape[0], r.shape[1], -1)
