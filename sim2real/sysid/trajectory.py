"""A validated recording in the model's terms: model-order arrays, noise levels, velocity estimates.

``Recording`` (``recordings.py``) is a file read and checked; a ``Trajectory`` is what every
consumer works on -- multiple-shooting predictions, inverse dynamics, SimOpt's real rollouts --
built once:

* positions ``q [T, nq]`` in model order, time from the recording's first sample;
* the noise of every measured signal, estimated from the data (the residual of a local cubic
  fit over 7 samples, robust to outliers; a quantised encoder's step when the signal moves in
  steps);
* the smoothing window chosen from the data: the widest Savitzky-Golay window (cubic) whose
  residual is still what the noise explains (wider would cut into the motion);
* velocities: the smoothed derivative of the positions, combined with a measured ``qvel``
  column (smoothed the same way) by inverse-variance weights, so a measured velocity counts
  as much as its noise allows; ``sigma_v`` is the resulting standard error, the smoothing's
  bias included (``smoothing_error``): a fit trusts a segment's start velocity no more than that;
* where a segment starts near a command's jump, its start velocity is estimated across the kink
  the force's step puts in the motion, or taken from the measured ``qvel`` (``start_velocity``);
* each signal's weight in the fits (``signal_scale``): its noise, and at least 1% of its spread,
  an angle's counted up to one turn's.
"""
from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
from scipy.ndimage import uniform_filter1d
from scipy.signal import savgol_coeffs, savgol_filter
from scipy.stats import f as f_dist


@dataclasses.dataclass
class Trajectory:
    """One recording as arrays ``[T, .]`` at its sample period ``dt`` (s).

    Attributes:
      name, path: the recording's.
      time: ``[T]`` seconds from the first sample.
      q: ``[T, nq]`` measured positions (m | rad), as measured (sensor offsets included).
      v: ``[T, nv]`` velocity estimate (m/s | rad/s); ``a``: acceleration ``[T, nv]`` (smoothed).
      ctrl: ``[T, nu]`` commands; ``qfrc``: ``[T, nv]`` known external forces (0 where none).
      force: ``[T, nu]`` measured actuator force, or None; ``qvel``: ``[T, nv]`` measured, or None.
      sigma_q, sigma_v: ``[nq]``, ``[nv]`` noise std of ``q`` and (RMS) standard error of ``v``.
      sigma_qvel, sigma_force: noise of the measured ``qvel`` / ``force`` columns (None if absent).
      window: Savitzky-Golay window (samples) used for ``v`` and ``a``.
      sigma_v_t: ``[T, nv]`` standard error of ``v`` at every sample (larger where the motion
        changes fast: the smoothing's local bias).
      same_q, same_v: the qpos and dof columns whose velocity is their position's rate (every one
        but a quaternion's; ``ModelColumns``); None: all of them (nq = nv).
    """

    name: str
    path: str
    dt: float
    time: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    ctrl: np.ndarray
    qfrc: np.ndarray
    force: np.ndarray | None
    qvel: np.ndarray | None
    sigma_q: np.ndarray
    sigma_v: np.ndarray
    sigma_qvel: np.ndarray | None
    sigma_force: np.ndarray | None
    window: int
    sigma_v_t: np.ndarray | None = None
    same_q: np.ndarray | None = None
    same_v: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.time)

    def part(self, start: int, stop: int) -> "Trajectory":
        """Samples ``start:stop`` (time still counted from the recording's first sample)."""
        s = slice(start, stop)
        cut = lambda x: None if x is None else x[s]  # noqa: E731
        return dataclasses.replace(self, time=self.time[s], q=self.q[s], v=self.v[s], a=self.a[s],
                                   ctrl=self.ctrl[s], qfrc=self.qfrc[s], force=cut(self.force),
                                   qvel=cut(self.qvel), sigma_v_t=cut(self.sigma_v_t))


# a signal's weight in the fits is 1 / (noise^2 + (SPREAD_FLOOR * its std)^2): a signal measured
# with almost no noise still does not outweigh every other one (``signal_scale``)
SPREAD_FLOOR = 0.01


# an angle's spread counts up to a turn's (the std of an angle spread evenly over one turn): a joint
# that turns over and over (a flywheel) has a spread that grows with how long it was recorded, and
# says nothing about how closely its motion must be predicted
TURN_STD = 2 * np.pi / np.sqrt(12)


def signal_scale(sigmas, values: np.ndarray, floor: float = SPREAD_FLOOR, angles=None) -> np.ndarray:
    """``[n]`` scale each column of ``values [T, n]`` is weighed with: the largest of its
    recordings' noise stds ``sigmas [R, n]``, combined with ``floor`` times its spread (for the
    columns ``angles [n]`` marks, at most ``TURN_STD``)."""
    spread = np.std(values, 0)
    if angles is not None:
        spread = np.where(angles, np.minimum(spread, TURN_STD), spread)
    return np.sqrt(np.max(sigmas, 0) ** 2 + (floor * spread) ** 2)


def moves(noise, spread):
    """Whether a signal moves beyond its noise (elementwise over ``[n]`` noise stds and spreads):
    its motion's own variance (``spread^2 - noise^2``) exceeds the noise's. A signal that does
    not (an encoder's count differenced at a fast rate; a joint held still by a stiff servo) has
    an error of about its noise for any model, and pooled with the others (a weight per residual,
    an NRMSE per signal) it dilutes every relative measure towards nothing."""
    return np.asarray(noise) < np.asarray(spread) / np.sqrt(2)


def turn_jumps(angle: np.ndarray) -> int:
    """How many times an angle ``[T]`` (rad) logged wrapped into one turn (an encoder's or
    ``joint_states``' +-pi) wraps: its jumps over pi, where every one is a whole turn within 1 rad;
    0 where it has none, or where one is not (a glitch is not a wrap)."""
    jumps = np.abs(np.diff(angle))
    big = jumps > np.pi
    return int(big.sum()) if big.any() and np.all(np.abs(jumps[big] - 2 * np.pi) < 1.0) else 0


def noise_std(x: np.ndarray) -> np.ndarray:
    """Per column of ``x [T, n]``: the std of white measurement noise on a smooth signal.

    The residual of a local cubic fit over 7 samples leaves the noise (times sqrt(1 - 7/21)) and
    almost none of a smooth signal; its median absolute deviation ignores outliers. A signal
    that moves in steps (an encoder) is quantised: its noise is the step / sqrt(12). It is
    recognised by often standing still, or by every change being a whole number of its smallest
    change (an encoder that moves about a count per sample seldom stands still, and there the
    fit's residual of the staircase is far below the step: a 4096-count encoder at 500 Hz read
    0.17 of a step instead of 0.29, and the smoothing window fell to its 7-sample minimum).
    """
    x = np.asarray(x, float)
    if len(x) < 9:
        return np.zeros(x.shape[1])
    res = x - savgol_filter(x, 7, 3, axis=0, mode="interp")
    mad = 1.4826 * np.median(np.abs(res - np.median(res, 0)), 0) / np.sqrt(1 - 7 / 21)
    return np.maximum(np.maximum(mad, quantisation_noise(x)), 1e-12 * (np.ptp(x, 0) + 1e-12))


def quantisation_noise(x: np.ndarray) -> np.ndarray:
    """Per column of ``x [T, n]``: a quantised signal's step / sqrt(12), else 0 (``noise_std``)."""
    out = np.zeros(x.shape[1])
    for k in range(x.shape[1]):
        d = np.diff(x[:, k])
        steps = np.abs(d[d != 0])
        if len(steps):
            smallest = np.min(steps)
            r = steps / smallest
            on_grid = np.mean(np.abs(r - np.round(r)) < 1e-3) > 0.99
            if on_grid or np.mean(d == 0) > 0.2:  # a quantised signal
                out[k] = float(smallest) / np.sqrt(12)
    return out


def choose_window(x: np.ndarray, sigma: np.ndarray, dt: float, max_seconds: float = 0.25) -> int:
    """The widest odd Savitzky-Golay window (cubic, >= 7 samples) whose residual on every column
    of ``x [T, n]`` stays within 1.3 times what the noise ``sigma [n]`` alone leaves."""
    best = 7
    limit = max(7, min(int(max_seconds / dt), len(x) // 4))
    for w in range(7, limit + 1, 2):
        c0 = savgol_coeffs(w, 3)[w // 2]
        expected = sigma * np.sqrt(max(1.0 - c0, 1e-6))
        res = np.sqrt(np.mean((x - savgol_filter(x, w, 3, axis=0, mode="interp")) ** 2, 0))
        if np.all(res <= 1.3 * expected + 1e-15):
            best = w
        else:
            break
    return best


# the columns of a joint with several coordinates, ``<joint>:<coordinate>``: a free joint's position
# (world frame) and orientation quaternion, then its linear (world frame) and angular (body frame)
# velocity, as MuJoCo orders ``qpos`` and ``qvel``; a ball joint's quaternion and angular velocity
_COORDS = {int(mujoco.mjtJoint.mjJNT_FREE): (("x", "y", "z", "qw", "qx", "qy", "qz"), ("vx", "vy", "vz", "wx", "wy", "wz")),
           int(mujoco.mjtJoint.mjJNT_BALL): (("qw", "qx", "qy", "qz"), ("wx", "wy", "wz"))}


class ModelColumns:
    """The recording columns a MuJoCo model reads, in model order: ``qpos:<joint>`` (and
    ``qvel:<joint>``, ``qfrc:<joint>``) per joint, ``ctrl:<actuator>`` (and ``force:<actuator>``)
    per actuator. A free or ball joint has one column per coordinate, ``qpos:<joint>:qw`` etc.
    (``_COORDS``). The diagnosis' ``System`` and SimOpt's recordings path both read through it.

    Attributes:
      qpos_names: ``[nq]`` column names after ``qpos:``; dof_names: ``[nv]`` after ``qvel:`` / ``qfrc:``.
      quats: ``[(qpos address, dof address)]`` of every orientation quaternion (free and ball joints).
      same_q, same_v: ``[k]`` the qpos and dof addresses of the coordinates whose velocity is their
        position's rate (hinges, slides, a free joint's position): every one where no quaternion is.

    ``source`` names the model in errors (a file path, or e.g. "the env's model").
    """

    def __init__(self, m: mujoco.MjModel, source: str):
        self.source = source
        self.joints = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(m.njnt)]
        self.actuators = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in range(m.nu)]
        self.nv = int(m.nv)
        self.dofadr = np.asarray(m.jnt_dofadr).copy()
        self.qpos_names, self.dof_names, self.quats, same_q, same_v = [], [], [], [], []
        self.hinges = []  # qpos addresses of the hinges (an angle logged wrapped is unwrapped: ``arrays``)
        self.notes: list[str] = []  # what ``arrays`` did to the data (a wrapped angle unwrapped)
        for j, name in enumerate(self.joints):
            t, qa, da = int(m.jnt_type[j]), int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
            if t in _COORDS:
                qc, vc = _COORDS[t]
                self.qpos_names += [f"{name}:{c}" for c in qc]
                self.dof_names += [f"{name}:{c}" for c in vc]
                lin = 3 if t == int(mujoco.mjtJoint.mjJNT_FREE) else 0
                same_q += range(qa, qa + lin)
                same_v += range(da, da + lin)
                self.quats.append((qa + lin, da + lin))
            else:
                self.qpos_names.append(name)
                self.dof_names.append(name)
                same_q.append(qa)
                same_v.append(da)
                if t == int(mujoco.mjtJoint.mjJNT_HINGE):
                    self.hinges.append(qa)
        self.same_q, self.same_v = np.array(same_q, int), np.array(same_v, int)

    def check_recording_covers(self, rec) -> None:
        """Every joint must be measured (the state is set from the data)."""
        missing = [j for j in self.qpos_names if rec.get("qpos", j) is None]
        if missing:
            from sim2real.sysid.recordings import RecordingError

            raise RecordingError(f"{rec.path}: no qpos column for joint coordinate(s) {', '.join(missing)} of the "
                                 f"model ({self.source}); every joint's position must be recorded")

    def arrays(self, rec):
        """Recording -> ``(qpos [T, nq], ctrl [T, nu], force [T, nu] or None, qfrc [T, nv])`` in model
        order. Quaternions are normalised and their signs made continuous (``q`` and ``-q`` are
        one orientation; a logger may switch between them). A hinge angle logged wrapped into one
        turn (an encoder's or ``joint_states``' +-pi) is unwrapped where every jump over pi is one
        of a whole turn, within 1 rad: a pendulum spinning over the top read as jumps of 2 pi was
        diagnosed `none` at a held-out NRMSE of 0.67 (``notes`` says where it was done)."""
        self.check_recording_covers(rec)
        T = len(rec)
        qpos = np.stack([rec.get("qpos", j) for j in self.qpos_names], -1)
        for qa in self.hinges:
            if n := turn_jumps(qpos[:, qa]):
                qpos[:, qa] = np.unwrap(qpos[:, qa])
                note = f"{rec.name}: qpos:{self.qpos_names[qa]} wraps around a turn ({n} jumps of 2 pi): unwrapped"
                if note not in self.notes:
                    self.notes.append(note)
        for qa, _ in self.quats:
            qpos[:, qa:qa + 4] = continuous_quaternions(qpos[:, qa:qa + 4], rec.path, self.qpos_names[qa])
        ctrl = (np.stack([rec.get("ctrl", a) for a in self.actuators], -1) if self.actuators
                else np.zeros((T, 0)))
        force = None
        if self.actuators and all(rec.get("force", a) is not None for a in self.actuators):
            force = np.stack([rec.get("force", a) for a in self.actuators], -1)
        qfrc = np.zeros((T, self.nv))
        for k, name in enumerate(self.dof_names):
            col = rec.get("qfrc", name)
            if col is not None:
                qfrc[:, k] = col
        return qpos, ctrl, force, qfrc

    def measured_qvel(self, rec) -> np.ndarray | None:
        """``[T, nv]`` measured velocities, or None unless every dof's column is there."""
        if not all(rec.get("qvel", j) is not None for j in self.dof_names):
            return None
        return np.stack([rec.get("qvel", j) for j in self.dof_names], -1)

    def rates(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """``[T, nv]`` velocities (or, given second derivatives, accelerations) from positions ``q``
        and their time derivative ``dq`` (``[T, nq]``). A quaternion's angular velocity in its body's
        frame, as MuJoCo's ``qvel`` holds it, is ``2 vec(conj(q) dq)``; its acceleration is the same
        with ``d2q`` (``conj(dq) dq`` is real, so its vector part vanishes)."""
        out = np.zeros(q.shape[:-1] + (self.nv,))
        out[..., self.same_v] = dq[..., self.same_q]
        for qa, da in self.quats:
            out[..., da:da + 3] = 2.0 * _quat_mul(_conj(q[..., qa:qa + 4]), dq[..., qa:qa + 4])[..., 1:]
        return out

    def dof_spread(self, per_q: np.ndarray) -> np.ndarray:
        """``[..., nv]`` an error per dof from errors ``per_q [..., nq]`` of the positions' columns
        (or of their rates): a quaternion's angular dof twice the RMS of its four components' (``rates``)."""
        out = np.zeros(per_q.shape[:-1] + (self.nv,))
        out[..., self.same_v] = per_q[..., self.same_q]
        for qa, da in self.quats:
            out[..., da:da + 3] = 2.0 * np.sqrt(np.mean(per_q[..., qa:qa + 4] ** 2, -1, keepdims=True))
        return out

    def q_spread(self, per_v: np.ndarray) -> np.ndarray:
        """``[..., nq]`` a spread per position column from one per dof ``per_v [..., nv]``: a
        quaternion's components move at half its angular velocity's RMS (``dq = q w / 2``)."""
        out = np.zeros(per_v.shape[:-1] + (len(self.qpos_names),))
        out[..., self.same_q] = per_v[..., self.same_v]
        for qa, da in self.quats:
            out[..., qa:qa + 4] = 0.5 * np.sqrt(np.mean(per_v[..., da:da + 3] ** 2, -1, keepdims=True))
        return out


def _conj(q):
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def _quat_mul(a, b):
    w1, x1, y1, z1 = np.moveaxis(a, -1, 0)
    w2, x2, y2, z2 = np.moveaxis(b, -1, 0)
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], -1)


def continuous_quaternions(q: np.ndarray, path: str = "", column: str = "") -> np.ndarray:
    """``[T, 4]`` unit quaternions (w, x, y, z) with each sample's sign the one nearer its
    predecessor's, so that the components are smooth in time; a zero quaternion is refused."""
    norm = np.linalg.norm(q, axis=-1)
    if np.any(norm < 1e-6):
        from sim2real.sysid.recordings import RecordingError

        row = int(np.argmax(norm < 1e-6))
        raise RecordingError(f"{path}: the quaternion in columns qpos:{column.rsplit(':', 1)[0]}:qw..qz is zero at "
                             f"data row {row + 1}")
    q = q / norm[:, None]
    flip = np.cumsum(np.concatenate([[0], np.sum(q[1:] * q[:-1], -1) < 0])) % 2 == 1
    return np.where(flip[:, None], -q, q)


def _smooth(x, w, dt, deriv):
    return savgol_filter(x, w, 3, deriv=deriv, delta=dt, axis=0, mode="interp")


def _smooth_measured(qvel, sigma_qvel, dt):
    """``(window, smoothed [T, nv])`` of a measured velocity column set (``from_recording``; the raw
    column's bend at a command's kink, ``_measured_start``)."""
    wv = choose_window(qvel, sigma_qvel, dt)
    return wv, _smooth(qvel, wv, dt, 0)


def smoothing_error(x: np.ndarray, w: int, sigma: np.ndarray, dt: float, deriv: int) -> np.ndarray:
    """``[T, n]`` error of the window-``w`` Savitzky-Golay estimate (``deriv``-th derivative) of
    each column of ``x [T, n]`` at every sample: its noise (``sigma``: the columns' white noise)
    and its local bias.

    A window wide enough that the *positions'* residual is only noise can still bend their
    derivative where the motion changes fast (a command step's onset, a PD loop's corrections),
    and only there. The bias is measured against a window a third as wide (less bent): what their
    difference holds beyond the noise the two windows leave differently, averaged over ``w``
    samples around each one, is the wider window's bias there (the narrow window's own, smaller
    bias is ignored, so this errs low)."""
    cw = savgol_coeffs(w, 3, deriv=deriv, delta=dt)
    noise = sigma * np.sqrt(np.sum(cw**2))
    n = max(7, (w // 3) | 1)
    if n >= w or len(x) < w:
        return np.broadcast_to(noise, x.shape).copy()
    cn = np.zeros(w)
    cn[(w - n) // 2: (w + n) // 2] = savgol_coeffs(n, 3, deriv=deriv, delta=dt)
    d2 = (_smooth(x, w, dt, deriv) - _smooth(x, n, dt, deriv)) ** 2
    local = uniform_filter1d(d2, w, axis=0, mode="nearest")
    bias2 = np.maximum(local - sigma**2 * np.sum((cw - cn) ** 2), 0.0)
    return np.sqrt(noise**2 + bias2)


def from_recording(rec, system, window: int | None = None, sigma_q: np.ndarray | None = None,
                   sigma_v: np.ndarray | None = None) -> Trajectory:
    """Build the trajectory of ``rec`` for ``system`` (a ``sysid.system.System`` or a
    :class:`ModelColumns`: what has ``arrays`` and ``joints``).

    ``window``: Savitzky-Golay window in samples (default: chosen from the data); ``sigma_q``:
    the positions' noise ``[nq]`` where it is known better than the data's smoothness tells
    (default: ``noise_std``; ``diagnose.rough_motion_noise``), and ``sigma_v`` ``[nv]`` the least
    standard error of the velocity estimates there.
    """
    qpos, ctrl, force, qfrc = system.arrays(rec)
    cols = getattr(system, "columns", system)
    dt = rec.dt
    sigma_q = noise_std(qpos) if sigma_q is None else np.asarray(sigma_q, float)
    w = window or choose_window(qpos, sigma_q, dt)
    w = min(w, len(qpos) - (1 - len(qpos) % 2))
    # velocities [nv] from the positions' derivatives [nq] (the same columns but for quaternions)
    q_s = _smooth(qpos, w, dt, 0) if cols.quats else qpos
    v = cols.rates(q_s, _smooth(qpos, w, dt, 1))
    a = cols.rates(q_s, _smooth(qpos, w, dt, 2))
    sigma_v_t = cols.dof_spread(smoothing_error(qpos, w, sigma_q, dt, 1))
    if sigma_v is not None:
        sigma_v_t = np.maximum(sigma_v_t, sigma_v)
    sigma_qvel = None
    qvel = cols.measured_qvel(rec)
    if qvel is not None:
        sigma_qvel = noise_std(qvel)
        wv, vm = _smooth_measured(qvel, sigma_qvel, dt)
        s_m = smoothing_error(qvel, wv, sigma_qvel, dt, 0)
        # inverse-variance combination of the two estimates, sample by sample (errors: noise and
        # the local smoothing bias)
        wq, wm = 1 / np.maximum(sigma_v_t, 1e-12) ** 2, 1 / np.maximum(s_m, 1e-12) ** 2
        v = (wq * v + wm * vm) / (wq + wm)
        sigma_v_t = 1 / np.sqrt(wq + wm)
    sigma_v = np.sqrt(np.mean(sigma_v_t**2, 0))
    sigma_force = noise_std(force) if force is not None else None
    return Trajectory(rec.name, rec.path, dt, rec.time - rec.time[0], qpos, v, a, ctrl, qfrc, force, qvel,
                      sigma_q, sigma_v, sigma_qvel, sigma_force, int(w), sigma_v_t,
                      *((cols.same_q, cols.same_v) if cols.quats else (None, None)))


def command_jumps(ctrl: np.ndarray, share: float = 0.05, typical: float = 10.0) -> np.ndarray:
    """Samples ``[k]`` at which some command column of ``ctrl [T, nu]`` jumps: by more than
    ``share`` of its spread and ``typical`` times its median change per sample (a step's or a
    PRBS switch's first sample; a smooth command has none, nor has a feedback loop's output whose
    every sample moves with the measurement noise, outside its reference's steps)."""
    if ctrl.shape[1] == 0 or len(ctrl) < 2:
        return np.zeros(0, int)
    du = np.abs(np.diff(ctrl, axis=0))
    spread = np.ptp(ctrl, 0)
    limit = np.maximum(share * np.where(spread > 0, spread, np.inf), typical * np.median(du, 0))
    return np.where((du > limit).any(1))[0] + 1


def start_velocity(tr: Trajectory, idx: np.ndarray, level: float = 0.99
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Velocity ``[k, nv]`` and acceleration just before ``[k, nv]`` at samples ``idx [k]`` of
    ``tr``, for starting simulations there, and ``opened [k, nv]``: True where a command jumps
    within the start's smoothing window and the kink cannot be refitted (a window of 7-11
    samples, too short for the refit's parameters; a quaternion's dofs; no measured ``qvel``):
    ``kink_error`` bounds the smoothed estimate's error there. (In a longer window the refit is
    tried, and where its F test fails the positions show no kink above their noise:
    ``smoothing_error`` stands.)

    A force that steps after a command jump puts a kink in the velocity (the acceleration jumps),
    and a cubic smoothing across it misses the velocity by up to ten times its noise (a
    flywheel's step at 500 Hz, window 51: 0.15 rad/s rms within the window of a step, 0.013 away
    from one), more than ``smoothing_error`` says; a simulation started there carries that error
    through its whole segment. So the window is refitted with the cubic plus, at each jump
    inside it, a jump of acceleration and of jerk. Where the force follows the command is the
    physics' business (a delay moves it), not the estimate's: the jumps are tried shifted by
    0, 1, ... half a window of samples together, the best shift kept, and that fit is used where
    an F test (``level``, divided among the shifts tried) says it explains the positions better
    than the cubic alone (windows with fewer than twice the samples of its parameters are not
    refitted); elsewhere the smoothed estimates are kept. Columns are judged one by one. Where
    ``qvel`` is measured, ``_measured_start`` instead."""
    idx = np.asarray(idx, int)
    v, a = tr.v[idx].copy(), tr.a[idx].copy()
    hw = tr.window // 2
    jumps = command_jumps(tr.ctrl)
    opened = np.zeros(v.shape, bool)
    if not len(jumps):
        return v, a, opened
    if tr.qvel is not None:
        return _measured_start(tr, idx, jumps, v), a, opened
    t = np.arange(-hw, hw + 1) * tr.dt
    cubic = np.stack([np.ones_like(t), t, t**2, t**3], 1)
    # (a quaternion's rate is not its angular velocity: its dofs keep the smoothed estimate)
    sq, sv = (slice(None), slice(None)) if tr.same_q is None else (tr.same_q, tr.same_v)
    near = np.min(np.abs(idx[:, None] - jumps[None]), 1) <= hw
    opened[near] = True
    opened[np.ix_(near, np.arange(v.shape[1])[sv])] = len(t) < 2 * (4 + 2)   # (too short to refit one jump)
    shifts = hw + 1
    for n, i in enumerate(idx):
        if i < hw or i + hw >= len(tr.q):
            continue
        y = tr.q[i - hw: i + hw + 1][:, sq]
        rss0 = np.sum((y - cubic @ np.linalg.lstsq(cubic, y, rcond=None)[0]) ** 2, 0)
        best = None
        for s in range(shifts):
            ks = jumps + s
            ks = ks[(ks > i - hw) & (ks < i + hw - 1)]  # (two samples after a jump, at least)
            if not len(ks) or len(t) < 2 * (4 + 2 * len(ks)):  # (twice the samples of parameters)
                continue
            tk = (ks - i) * tr.dt
            ramps = [np.maximum(t - x, 0.0) for x in tk]
            A = np.concatenate([cubic, np.stack([r**p for r in ramps for p in (2, 3)], 1)], 1)
            c = np.linalg.lstsq(A, y, rcond=None)[0]
            rss1 = np.sum((y - A @ c) ** 2, 0)
            if best is None or rss1.sum() < best[0].sum():
                best = (rss1, tk, c)
        if best is None:
            continue
        rss1, tk, c = best
        extra, free = 2 * len(tk), len(t) - 4 - 2 * len(tk)
        F = (rss0 - rss1) / extra / np.maximum(rss1 / free, 1e-300)
        ok = F > f_dist.ppf(1 - (1 - level) / shifts, extra, free)
        # derivatives at t = 0 (a jump exactly there counts as after: the acceleration *before*
        # the start is the one a semi-implicit step's state lags by, ``velocity_state``)
        before = np.maximum(-tk, 0.0)
        dv = np.concatenate([[0.0, 1.0, 0.0, 0.0], np.ravel([[2 * b, 3 * b**2] for b in before])])
        da = np.concatenate([[0.0, 0.0, 2.0, 0.0], np.ravel([[2.0 * (b > 0), 6 * b] for b in before])])
        v[n, sv] = np.where(ok, dv @ c, v[n, sv])
        a[n, sv] = np.where(ok, da @ c, a[n, sv])
    return v, a, opened


def kink_error(tr: Trajectory, idx: np.ndarray, opened: np.ndarray, v0: np.ndarray, m: mujoco.MjModel) -> np.ndarray:
    """``[k, nv]``: how far a command's kink can bend the smoothed start velocities where
    ``opened [k, nv]`` (``start_velocity``) at samples ``idx [k]``, from the acceleration jump the
    model itself puts in the motion there (0 elsewhere).

    Where the window is too short to refit the kink (7-11 samples: a fast motion logged at
    100 Hz), the cubic's velocity across a jump of acceleration ``da`` at time ``tau`` is off by
    ``da * g(tau)`` (``g``: the window's derivative weights on a ramp starting at ``tau``, minus
    its true slope at 0) -- on a ball-jointed arm's torque steps 0.8 rad/s rms against an error
    estimate of 0.02, which a fit could only blame on a false delay. ``da`` is the nominal
    model's: its accelerations at the start state ``v0 [k, nv]`` under the command before and
    after each jump (``mj_forward``: actuator gains, moment arms and the mass matrix as the
    simulation has them; an actuator with an activation does not jump). ``tau`` is the jump's
    time or later (a delay moves the kink), the largest ``|g|`` kept. On such a swing the bound
    is 1.1 to 39 times the error where the error is above three times its estimate (median 3.3:
    loose where the step's transient dies within the window; ``tests/test_floating_base.py``).
    """
    err = np.zeros(opened.shape)
    rows = np.where(opened.any(1))[0]
    if not len(rows):
        return err
    jumps = command_jumps(tr.ctrl)
    hw = tr.window // 2
    t = np.arange(-hw, hw + 1) * tr.dt
    cw = savgol_coeffs(tr.window, 3, deriv=1, delta=tr.dt, use="dot")
    d = mujoco.MjData(m)
    for n in rows:
        i = int(idx[n])
        for k in jumps[np.abs(jumps - i) <= hw]:
            taus = np.linspace((k - i - 0.5) * tr.dt, hw * tr.dt, 4 * tr.window)
            g = max(abs(cw @ (np.maximum(t - x, 0.0) ** 2 / 2) - max(-x, 0.0)) for x in taus)
            acc = []
            for u in (tr.ctrl[k - 1], tr.ctrl[k]):
                d.qpos[:], d.qvel[:], d.ctrl[:] = tr.q[i], v0[n], u
                mujoco.mj_forward(m, d)
                acc.append(d.qacc.copy())
            err[n] += g * np.abs(acc[1] - acc[0])
    return np.where(opened, err, 0.0)


def _measured_start(tr: Trajectory, idx: np.ndarray, jumps: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``start_velocity`` where ``qvel`` is measured: its smoothing bends at a command's kink as the
    positions' does (more where a backlash closes: a gantry's step at 100 Hz, window 7, misses
    the velocity by 0.024-0.053 rad/s rms near the steps where the raw column's noise is 0.003),
    and there the raw measurement, unbiased, is the better start: used at each start within a
    smoothing window of a jump where the measured column's residual from its smoothing, over the
    5 samples around it, is above twice its noise (a bend, not noise)."""
    wv, vm = _smooth_measured(tr.qvel, tr.sigma_qvel, tr.dt)
    hw = max(tr.window, wv) // 2
    for n, i in enumerate(idx):
        if not np.any(np.abs(jumps - i) <= hw):
            continue
        lo, hi = max(i - 2, 0), min(i + 3, len(vm))
        bent = np.sqrt(np.mean((tr.qvel[lo:hi] - vm[lo:hi]) ** 2, 0)) > 2 * tr.sigma_qvel
        v[n] = np.where(bent, tr.qvel[i], v[n])
    return v
