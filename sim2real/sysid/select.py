"""Name the missing physics: screen every candidate, fit the best, add effects while they hold up.

Forward selection on the simulation error (``fit.py``):

1. ``none``: the nominal parameters (masses, declared damping and friction) re-fitted.
2. Screen: every candidate at every point of its grid is simulated once with the current
   model's other parameters; the current parameters and segment velocities are then re-solved
   *linearly* (the current model's Jacobian), and the effect's own magnitude too (the difference
   between neighbouring grid points is its Jacobian column). The drop of the objective is the
   candidate's score -- a Rao score test, in effect, that needs no fit per candidate. Where the
   re-fit moved a nominal parameter far (it may have taken up the missing effect), the same is
   done from the model's own nominal values (``_bases``); each candidate starts from the better.
3. The ``top`` candidates by score are fitted in full (Gauss-Newton from their best grid point,
   every parameter of the current model free), then judged on the *validation* segments (the
   tail of every training recording, never fitted): each segment's prediction error, with its
   initial velocity refined, for the current model and the candidate. A candidate passes when
   the validation error falls by ``min_gain`` (relative) and the per-segment differences are
   significant (paired t over the segments >= ``min_t``, ``Selector.judge``). Of those that pass,
   the one with the lowest error on the fitted and validation segments together joins the model.
4. Repeat from 2 until nothing passes (or ``max_effects``). Then each named effect of a model
   with two or more is tried replaced by what screens best in its place (``_swap``), and a
   delay on a model with several actuators by one lag they share, and a named backlash by the
   rotor inertia of its joint where that predicts far better (``_in_place``).
5. Backward check (``_prune``): each named effect must still pass the test against the model
   without it; the weakest that fails is dropped, until all pass.

Every decision is judged against two floors (``SelectConfig``): the misfit must exceed what the
physics step alone causes, measured per diagnosis (``step_level``), and a tiny absolute level.
A candidate that passes everything but the step's floor is judged again with a physics step
``finer`` times shorter (``_finer_passes``): an effect that only absorbed the integrator's error
loses its gain there, a real one keeps it.

A fit whose effect ends at its absent value (``Candidate.is_off``) never names it: its gain is a
better fit of the current hypothesis, which replaces the current model before the round runs
again. When no single effect passes on the nominal model but one lowers the validation error, it
is fitted together with each of the next best, and with the candidates that screen best on top
of it (``_pair``): two effects that only together explain the data. Where no pair passes either,
a Coulomb friction is fitted on every joint at once (``_group``): an arm that rubs at each joint.

A Coulomb friction that passes is then tried with a level per direction (``coulomb_asym``),
kept by the same test. A fit whose effect parameter ends at the edge of its search range is
widened once and fitted again.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from sim2real.physics.kinds.base import actuator_joint
from sim2real.sysid.candidates import Candidate
from sim2real.sysid.fit import Fitter, Result

# a validation segment's error is floored at this many residuals (each in units of its noise) in
# the paired test (``Selector.judge``)
KAPPA = 0.1
# ... and a segment both models predict within this fraction of that floor is left out of the
# test (a tie; ``Selector._judge``)
TIE = 0.2
# a re-fit that moved a nominal parameter by more than this fraction of its value is screened from
# the nominal values too (``Selector._bases``)
RESET_MOVE = 0.25
FAR_MASS = 10.0  # a re-fitted mass this many times above or below the model's stands in for other physics


def is_far_mass(nominal: float, fitted: float) -> bool:
    """A re-fitted mass more than ``FAR_MASS`` times above or below the model's: not a measurement
    of the body (``diagnose.far_masses`` reports it; ``SelectConfig.plausible_masses``)."""
    return nominal > 0 and not 1 / FAR_MASS <= fitted / nominal <= FAR_MASS


@dataclasses.dataclass
class Model:
    """A fitted hypothesis: the nominal re-fit plus ``effects`` (in the order found)."""

    effects: list           # [Candidate]
    result: Result
    val: np.ndarray         # per validation segment objective (velocities refined)
    params: list            # every free parameter's name
    refined: bool = False   # re-fitted from a better start found by a trial (``_absent_effect_gain``)

    @property
    def z(self):
        return self.result.z

    @property
    def label(self) -> str:
        return " + ".join(c.label for c in self.effects) or "none"


@dataclasses.dataclass
class Trial:
    """A candidate screened, fitted and judged against the model it would extend."""

    candidate: Candidate
    score: float            # screen: relative drop of the objective (linearised)
    model: Model | None = None
    val_ratio: float = float("nan")
    t: float = float("nan")
    passed: bool = False
    base_level: float = float("nan")
    note: str = ""
    others: list = dataclasses.field(default_factory=list)  # more starts: [(start, (z, v) base)] at other widths
    finer: bool = False     # judged at the finer step too (``Selector._finer_passes``)


@dataclasses.dataclass
class SelectConfig:
    """Thresholds of the selection, tuned on the tuning half of the independent benchmark and the
    EMPS recordings only (``benchmarks/results/diagnosis_independent/tuning.md`` says how).

    Attributes:
      min_gain: a candidate must lower the validation error by this fraction ...
      min_gain_first: ... or by this fraction when it is the first effect, on the nominal re-fit
        (there the step floor below and the backward check guard against an effect that absorbs
        noise; after a named effect, what is left is mostly the data's own precision, and a small
        gain there names a false second effect: tuning half, a delay beside a sensor offset) ...
      min_t: ... with a paired t-statistic over the validation segments at least this large ...
      floor_level: ... and, unless its gain is ``strong``, the model it extends must misfit the
        data by more than this: its validation objective per residual, or its fitted segments'
        if larger (``Selector.level``; residuals are in units of each signal's noise, at least 1%
        of its spread) ...
      floor_step: ... and by more than this many times the misfit the physics step alone causes
        (``step_level``, measured per diagnosis by ``diagnose.discretization_level``). A model
        whose remaining misfit the step's own error could explain has nothing left that an
        effect could be trusted with: a damping, a lag would absorb the integrator's error.
        Twice, not once: ``step_level`` is measured from noisy measured states and so
        understates what the step does to a fitted prediction (a servo pendulum at 1 ms whose
        whole misfit, 1.27 times its measured level, a damping took up); between once and twice
        the ``finer`` check decides (``tuning.md`` step 24).
      strong: a validation ratio at or below this passes whatever the misfit level.
      finer: a candidate that passes every test but ``floor_step`` is judged again, the model it
        extends and it, with a physics step this many times shorter (the same parameters,
        velocities refined): it passes if its gain holds there, by the same ratio and t, on a
        model misfitting by more than ``floor_level`` (0 or 1: such a candidate fails). That
        step's own measured floor is not asked: the gain kept is the evidence, and the measured
        floor can sit above the whole misfit of a model whose fit took the step's error up
        (a servo's start-up transient, 6.8 against 0.28 per residual on the focus list's 3051).
        On the two tuning lists' 216 cases, of 48 such checks 37 failed, each by its ratio or t,
        among them every candidate on a parameter-only case; three false candidates passed and
        lost to the true effect in their round (``tuning.md`` step 46).
      finer_refit: before that judgment both models are re-fitted at the finer step (this many
        Gauss-Newton steps from their own parameters): fitted at the diagnosis' step, their
        parameters carry that step's error, and simulated at the finer one with them the model
        extended misfits more than at its own step (an RC servo's 1128: 0.21 per residual at
        the chosen step, 0.50 at the finer; re-fitted there, 0.07), which hides a real effect's
        gain (its damping: ratio 0.78, t = 1.1; re-fitted, 0.095, t = 5.1). ``tuning.md`` step 68.
      finer_ratio: ... and there the candidate must lower the validation error to this fraction
        or below. Re-fitted at the finer step, models that already fit within a fraction of the
        data's precision let small gains through (a damping beside a right payload, a joint
        stiffness for an unmodelled band: ratios 0.71-0.78 at misfits of 0.014-0.016 per
        residual), where every true effect that took this check on the tuning half and the focus
        list kept a ratio of 0.46 or lower. 0.65, not 0.5: over all eight tuning lists true
        effects failed it at 0.56-0.63 (a gantry's band alone, 1064; a linear axis's friction
        beside its delay, 6096), and the false ones between 0.5 and 0.65 that passed it all lost
        in their round (``tuning.md`` step 81). What stops a parameter-only case there is the
        absolute floor, not this ratio (an RC servo's 090: a damping at 0.56, t = 5.3, on a model
        misfitting 0.0009 per residual at the finer step).
      top: candidates fitted per round; max_effects: effects named at most;
      min_score: candidates scoring less in the screen are not fitted; iters: Gauss-Newton steps.
      plausible_masses: of the candidates that pass, one whose fit keeps every body's mass within
        ``FAR_MASS`` of the model's is preferred to one that needs a mass far off: a user's model
        gets its masses roughly right, and a mass 50x off stands in for physics the effect leaves
        unexplained (a flywheel whose backlash a motor lag "explained" with the wheel at 1/58 of
        its mass). Only where none passes with plausible masses does the best of the rest join.
        Before that choice, a passing fit that needs a far mass is fitted again with the masses
        held at the model's, and replaces the first where it passes too (``_at_model_masses``:
        a servo at its force limit lets mass and force scale together; ``tuning.md`` step 66).
      backlash_starts: a backlash is fitted from the best points at this many widths of its grid,
        and the fit with the lowest training objective is kept. The band's effect on the motion
        changes in steps as it widens (the motor side's impacts come and go), so a fit moves its
        width little from where it starts: one start can hold it at the grid's narrowest width
        where the plant's is 8 times wider (the focus list's 3013). Every start is a compliant
        mesh (``band_starts``): fitted from a rigid one, width, inertia and stiffness stay where
        they start; from a compliant one they move to the plant's (the focus list's 3025 and
        3033: validation ratio 1.7 and 0.97 from the screen's rigid points, 0.09 and 0.02 from
        its compliant ones; ``tuning.md`` steps 47-48). A payload is fitted from its best point
        alone: from three, its masses moved further from the truth (``tuning.md`` steps 27 and 45).
      geared: once a Coulomb friction is named on a joint, a backlash on its actuator is fitted in
        the next rounds whatever its screen score (a gear train has both). The screen scores a
        band by a linearisation in its width alone, and beside a named friction that score
        ranked the true band below the four fitted in 8 of the pairs list's 20 misses
        (``tuning.md`` step 62); it is still judged by every test.
      band_scan: after those fits, this many widths over the band's searched range are simulated
        at once with the best fit's other parameters; if one fits the segments better, the fit
        starts again from it (0: no scan). The grid's widths are 2.5x apart, so a plant's band
        between two of them can be out of every start's reach (the extra list's 1004: fitted at
        0.0095 rad against 0.03, a motor lag beside it taking up the rest; ``tuning.md`` step 50).
      band_shown: a backlash that passes with its width at the bottom of its searched range is
        fitted again with its band closed (the width held at a thousandth of that bottom, the
        motor side's inertia and mesh and every other parameter fitted), and is named only if the
        band passes against that too (by ``min_gain`` and ``min_t``). The motor side alone,
        coupled through the mesh, is an inertia added to the joint and a compliance: it stands in
        for a payload (the combos list: a payload beside a right friction named a 1 mrad band in
        two cases). Asked of every passing band, the check failed 8 true bands of the pairs
        list's 23 whose fits kept their widths: there the motor side carries most of the gain
        too, so only a band the fit shrank to nothing is asked (``tuning.md`` step 69).
      timing_restart: on top of a model with an action delay or motor lag, a candidate that is not a
        timing effect is also fitted from the model's delays and lags scaled by this factor (0:
        off). Fitted alone, a delay or lag takes up whatever else slows the response, and the joint
        fit from there does not cross back: the combos list's 6098 (a linear axis, an 8.3 ms delay +
        a force limit) fitted its delay at 19.9 ms alone, and on top of it the limit went out of
        reach (objective 1.8e4); from half the delay, 10.6 ms and the limit (494: 0.027 of the fit
        from the delay). The restart is there to reach another basin: its fit is kept only where it
        brings the training objective under ``RESTART_MARGIN`` of the other's. Kept wherever it was
        1% lower (the device's CPUs: 23 restarts in 19 of 189 cases), it moved one right answer,
        6022's, to wrong (a friction on top of a right delay, 0.982 from half of it, predicted the
        validation segments worse); every other restart that was kept fitted 0.72-0.99 of the first
        fit, but 3803's (0.26, its candidate failing either way). ``tuning.md`` step 73.
      freeze_at_noise: every fit's steps leave put only the directions the data's noise leaves
        undetermined, not those the start's own misfit does (``Fitter.fit``'s ``at_noise``;
        ``tuning.md`` step 77).
      pair_screen: in the pair search (``Selector._pair``) the candidates not fitted this round are
        screened on top of the best fit, and this many of the best of them (by ``min_score``) are
        fitted together with it too (0: off). ``tuning.md`` step 80.
      timing_relative: where an action delay and a motor lag both pass, the one whose fitted
        segments' and validation segments' errors have the lower product is taken, not the one
        whose sum is lower (``Selector.best``). ``tuning.md`` step 83.
      swap: after the forward selection, each named effect of a model with two or more is taken
        out in turn, the candidates not named are screened on top of the rest, and the best is
        fitted there; it replaces the effect where that model passes the test against the one
        named (``Selector._swap``, sequential replacement). A stand-in named first hides what it
        stands in for: beside a band that passed the first round for a linear axis's delay, the
        delay never screened above zero (the combos list's 6097: screened on top of the friction
        alone, the delay replaces the band at a validation ratio of 0.22). ``tuning.md`` step 86.
      shared_lag: a named action delay on a model with several actuators is fitted again as one
        first-order lag shared by every actuator (``motor_lag_all``, otherwise searched only when
        asked: as a candidate of every round it named false shared lags, ``tuning.md`` step 59);
        the lag replaces the delay where it passes the test against the model with the delay
        (``Selector._shared_lag``). Identical drives lag alike, and a delay of every command
        stands in for their lag better than any one actuator's lag does: a 2-link arm whose two
        motors lag 30 ms was named a 27 ms delay (held-out error 0.074 -> 0.0082), the shared
        lag 29.9 ms when asked (-> 0.0024).
      rotor: a backlash named on an actuator is fitted again as a rotor inertia on the joint it
        drives (``rotor_inertia``, otherwise searched only when asked), which replaces the band
        where it passes the test against the model with the band and predicts the validation
        segments at least ``1 / rotor_ratio`` times better. A geared motor's rotor adds inertia
        without weight; left out of a pendulum's model (0.01 kg m^2), it was named a backlash
        whose motor-side inertia (0.0064) stood in for it (held-out 0.0188 -> 0.0019; the rotor,
        asked for: 0.009993, -> 0.000096; validation ratio 0.005 against the band).
      rotor_ratio: the validation ratio (rotor / band) under which the rotor replaces a band. A
        band nests the rotor (its motor-side inertia, the band closed), so a real band loses
        little to it; but the benchmark's bands are a dead zone *and* a motor-side inertia the
        model lacks, and with the test alone (``tuning.md`` step 93) the rotor replaced one of the
        tuning lists' 67 named bands, a true one (the focus list's 3064 at 0.475, the lowest of
        the 64 rotors fitted there: 0.475-4.5). 0.25 lies between that and the pendulum's 0.005
        (``tuning.md`` step 94; on 465 tuning-list cases run again it named no rotor); the arm
        of ``sixth_wave.py`` (0.70-0.79) keeps its false band.
      prune_fit: the backward check keeps an effect whose removal multiplies the fitted segments'
        objective by more than this, whatever the validation segments say (0: no such rule). A
        stand-in that lost its reason no longer carries the fit; an effect the rest cannot
        replace by a factor of 10 on most of the data is not one, and validation tails that
        disagree see less than the fit does (a fallen hopper's tails kept a thigh motor's lag
        and dropped the shared lag of all three motors that fitted 96x better, plant 40 ms on
        all three: ``benchmarks/results/closed_loop_warm_std_hopper/NOTE.md``).
      group: effects fitted on every joint that offers them at once where no single effect nor pair
        passes on the nominal model (``_group``): real arms rub at every joint, and on a vertical
        3-link arm with 0.1 N m on each (``new_user_probes/eighth_wave.py``) no joint's friction
        alone lowered the validation error (ratio 1.02) while the plant's model predicted the
        held-out data 11x better than the re-fitted one. Empty: never.
    """

    min_gain: float = 0.05
    min_t: float = 2.0
    min_gain_first: float = 0.02
    floor_level: float = 0.003
    strong: float = 0.0
    top: int = 4
    max_effects: int = 3
    min_score: float = 0.01
    iters: int = 6
    floor_step: float = 2.0
    finer: int = 4
    finer_refit: int = 3
    finer_ratio: float = 0.65
    plausible_masses: bool = True
    geared: bool = True
    backlash_starts: int = 3
    band_scan: int = 12
    band_shown: bool = True
    timing_restart: float = 0.5
    freeze_at_noise: bool = True
    pair_screen: int = 2
    timing_relative: bool = True
    swap: bool = True
    prune_fit: float = 10.0
    shared_lag: bool = True
    rotor: bool = True
    rotor_ratio: float = 0.25
    group: tuple = ("coulomb_friction",)


TIMING = ("action_delay", "motor_lag")
RESTART_MARGIN = 0.5  # (``SelectConfig.timing_restart``)
PAIR_TRAIN = 0.5  # (``Selector._pair``) a fit this far below the model's training objective may be half of a pair
_UNBUILT = object()  # the finer fitter before its first use (it may be None once built)


def _paired_t(d: np.ndarray) -> float:
    """One-sample t-statistic of the per-segment improvements ``d`` (inf/0 when they do not vary)."""
    if len(d) < 3 or np.std(d) == 0:
        return float("inf") if np.mean(d) > 0 else 0.0
    return float(np.mean(d) / (np.std(d, ddof=1) / np.sqrt(len(d))))


def good_fit(trials: list, M) -> float:
    """The lowest training objective of ``trials``' fits, as a fraction of ``M``'s."""
    return min(t.model.result.phi for t in trials) / max(M.result.phi, 1e-300)


def band_starts(points: list, n: int) -> list:
    """Where a backlash's fits start: the best point at each width of its grid, at most ``n``,
    lowest linearised objective first (``[(phi, start, base index)]``). ``points``: ``[(phi,
    start, base index, grid point)]``, a grid point being ``(width, inertia[, stiffness])``.
    Where the grid has a stiffness, only compliant meshes (stiffness > 0) start a fit: a rigid
    mesh's fit does not move from its start (its impacts make the objective a staircase in the
    width, and the stiffness cannot leave 0, which stands for rigid), while one from a compliant
    point moves width, inertia and stiffness to the plant's. The rigid points still score the
    candidate in the screen (``SelectConfig.backlash_starts``)."""
    per_width = {}
    for phi, start, bi, g in points:
        if (len(g) < 3 or g[2] > 0) and phi < per_width.get(g[0], (np.inf,))[0]:
            per_width[g[0]] = (phi, start, bi)
    return sorted(per_width.values(), key=lambda x: x[0])[:n]


def _at_edge(c: Candidate, v: float) -> bool:
    """``v`` (the candidate's first parameter) ended at the edge of its search range that widening
    moves: the top for timing effects, backlash and a payload (5x its body's mass, which the load
    on a light link can pass), the bottom for a saturation."""
    return ((c.effect in ("motor_lag", "action_delay", "backlash", "mass_offset") and c.at_top(v))
            or (c.effect == "actuator_saturation" and c.at_bottom(v)))


class Selector:
    """Forward selection over ``candidates`` with ``fitter`` on the fit/validation segments."""

    def __init__(self, fitter: Fitter, nominal: list[str], candidates: list[Candidate], cfg: SelectConfig,
                 progress=None, step_level: float = 0.0, finer=None, allowed=None, shared=None, rotors=None):
        """``finer(k)``: the fitter of the same segments with a physics step ``k`` times shorter,
        or None where none can be built (``SelectConfig.finer``);
        ``allowed``: the parameter names an effect may use (None: any; ``DiagnoseConfig.expressible``),
        which decides whether a friction may get a level per direction;
        ``shared``: the lag shared by every actuator (a ``motor_lag_all`` candidate) fitted in place
        of a named delay (``SelectConfig.shared_lag``), or None;
        ``rotors``: per actuator, the rotor inertia (a ``rotor_inertia`` candidate) of the joint it
        drives, fitted in place of a backlash named on it (``SelectConfig.rotor``)."""
        self.f, self.nominal, self.cands, self.cfg = fitter, list(nominal), list(candidates), cfg
        self.shared, self.rotors = shared, dict(rotors or {})
        self.step_level = float(step_level)
        self._finer, self._fine = finer, _UNBUILT
        self._fine_fits: dict = {}
        self._dropped: dict = {}        # (id(M), id(c)) -> (M, c, M without c): ``_without``'s fits
        self.allowed = None if allowed is None else set(allowed)
        sh = fitter.sh
        self.fit_tiles, self.val_tiles = sh.tiles.of("fit"), sh.tiles.of("val")
        self.spec = sh.sys.spec
        self.progress = progress or (lambda text: None)
        self.rounds: list[list[Trial]] = []
        self.refits: list[str] = []     # models re-fitted from a better start (``_absent_effect_gain``)
        self.pruned: list[str] = []     # effects dropped by the backward check (``_prune``)
        self.units: list[frozenset] = []  # labels of pairs that joined together (``_pair``), judged as one
        self.groups: list[frozenset] = []  # labels of an effect's group on every joint (``_group``)

    # ------------------------------------------------------------------------------------------
    def _scales(self, effects) -> dict:
        sc = {n: self.f.scales[n] for n in self.nominal}
        for c in effects:
            for n in c.params:
                sc[n] = c.scale_of(n)
        return sc

    def fit(self, effects: list[Candidate], z0, v0, extra: tuple = (), hold: tuple = ()) -> Model:
        """Fit the nominal parameters, ``effects``' and ``extra`` together from ``z0`` (those in
        ``hold`` kept at their values in ``z0``)."""
        params = [n for n in list(self.nominal) + [n for c in effects for n in c.params] + list(extra) if n not in hold]
        return Model(list(effects), self._fit_with(self.f, effects, z0, v0, params, self.cfg.iters), None, params)

    def _fit_with(self, fitter, effects: list[Candidate], z0, v0, params: list, iters: int):
        """``params`` fitted from ``z0`` by ``fitter`` (this step's or the finer one's), each
        effect's inside its search range."""
        fitter.scales.update(self._scales(effects))
        bounds = {n: r for c in effects for n, r in zip(c.params, c.search)}
        return fitter.fit(z0, v0, params, self.fit_tiles, iters=iters, bounds=bounds, at_noise=self.cfg.freeze_at_noise)

    def validate(self, models: list[Model]) -> None:
        """Each model's per-segment validation objective (velocities refined), simulated together."""
        todo = [M for M in models if M.val is None]
        if todo:
            out = self.f.velocities_many([M.z for M in todo], [self.f.v_hat] * len(todo), self.val_tiles)
            for M, (_, per) in zip(todo, out):
                M.val = per

    def none(self) -> Model:
        M = self.fit([], self.spec.default.copy(), self.f.v_hat)
        self.validate([M])
        return M

    # ------------------------------------------------------------------------------------------
    def _lin_phi(self, r, J_t, J_v, v0, E=None, e_range=None, e_now=None):
        """Linearised minimum of the objective from residual ``r`` when the current parameters,
        the segment velocities and (``E [k, m, 1]``) the effect's magnitude move; returns
        ``(phi, effect step)``. The effect stays inside ``e_range``."""
        tiles = self.fit_tiles
        phi0 = self.f.phi(r, v0, tiles)

        def solve(Jt):
            # quadratic model |r + J d|^2: its minimum is phi0 - (velocity part) - g' H^-1 g
            H, g, _, v_gain = self.f._reduce(r, Jt, J_v, v0, tiles)
            if not len(g):
                return phi0 - v_gain, np.zeros(0)
            w, V = np.linalg.eigh(0.5 * (H + H.T))
            keep = w > 1e-9 * max(w.max(), 1e-30)
            gv = V.T @ g
            d = np.where(keep, -gv / np.maximum(w, 1e-300), 0.0)
            return phi0 - v_gain + float(gv @ d), V @ d

        if E is None:
            return solve(J_t)[0], None
        phi, d = solve(np.concatenate([J_t, E], -1))
        de = d[-1]
        if e_range is not None and not (e_range[0] <= e_now + de <= e_range[1]):
            de = float(np.clip(e_now + de, *e_range) - e_now)
            phi = solve(J_t)[0] if de == 0 else self._lin_phi(r + E[..., 0] * de, J_t, J_v, v0)[0]
        return phi, de

    def _bases(self, M: Model) -> list[tuple[np.ndarray, np.ndarray]]:
        """Where candidates are screened and fitted from: ``M`` itself, and ``M`` with its nominal
        parameters back at the model's own values (velocities: the data's estimate) when the
        re-fit moved any of them by more than ``RESET_MOVE`` of its value. A re-fit that lacks an
        effect can take it up with absurd values (a 25 ms lag as a 4x heavier, 40x damped
        carriage); from there a fit of the right effect only finds a local minimum near them."""
        bases = [(M.z, M.result.v0)]
        idx = self.spec.indices(self.nominal)
        moved = np.abs(M.z[idx] - self.spec.default[idx]) > RESET_MOVE * np.abs(self.spec.default[idx])
        if moved.any():
            z = M.z.copy()
            z[idx] = self.spec.default[idx]
            bases.append((z, self.f.v_hat.copy()))
        return bases

    def screen(self, M: Model, cands: list[Candidate]) -> list[Trial]:
        """Score every candidate at the current model ``M`` (see the module docstring), from each
        of ``_bases(M)``; a candidate keeps the base and start with the lowest linearised objective
        (a backlash: among its compliant meshes, ``band_starts``; its score counts every point)."""
        f, tiles = self.f, self.fit_tiles
        bases = self._bases(M)
        lin = []
        for z_b, v_b in bases:
            r_b, J_t, J_v = f.jacobian(z_b, v_b, M.params, tiles)
            lin.append((J_t, J_v, v_b, self._lin_phi(r_b, J_t, J_v, v_b)[0]))
        base = lin[0][3]
        zs, vs, owner = [], [], []
        for bi, (z_b, v_b) in enumerate(bases):
            for ci, c in enumerate(cands):
                for gi, g in enumerate(c.grid):
                    z = z_b.copy()
                    z[self.spec.indices(list(c.params))] = g
                    zs.append(z)
                    vs.append(v_b)
                    owner.append((bi, ci, gi))
        rs = f.residuals(np.stack(zs), np.stack(vs), tiles) if zs else []
        by = {}
        for (bi, ci, gi), r in zip(owner, rs):
            by.setdefault((bi, ci), {})[gi] = r
        trials = []
        for ci, c in enumerate(cands):
            best = (np.inf, None, 0)
            points = []
            grid = c.grid
            for bi, (J_t, J_v, v0, _) in enumerate(lin):
                for gi, g in enumerate(grid):
                    r = by[bi, ci][gi]
                    E, rng, now = None, None, None
                    if len(c.params) == 1 and len(grid) > 1:  # the effect's column from the nearest grid point
                        nb = gi + 1 if gi + 1 < len(grid) else gi - 1
                        step = grid[nb][0] - g[0]
                        if step != 0 and np.sign(grid[nb][0]) == np.sign(g[0] or grid[nb][0]):
                            E = ((by[bi, ci][nb] - r) / step)[..., None]
                            # the linear model holds between the grid neighbours only: the start stays there
                            lo_n = grid[max(gi - 1, 0)][0]
                            hi_n = grid[min(gi + 1, len(grid) - 1)][0]
                            rng = (max(min(lo_n, hi_n), c.search[0][0]), min(max(lo_n, hi_n), c.search[0][1]))
                            now = g[0]
                    phi, de = self._lin_phi(r, J_t, J_v, v0, E, rng, now)
                    start = list(g)
                    if de is not None:
                        start[0] = g[0] + de
                    if phi < best[0]:
                        best = (phi, tuple(start), bi)
                    points.append((phi, tuple(start), bi, g))
            score = (base - best[0]) / max(base, 1e-300)
            t = Trial(c, float(score))
            t.start = best[1]
            t.base = bases[best[2]]
            t.from_nominal = best[2] > 0
            if c.effect == "backlash" and (starts := band_starts(points, max(self.cfg.backlash_starts, 1))):
                (_, t.start, bi), more = starts[0], starts[1:]
                t.base, t.from_nominal = bases[bi], bi > 0
                t.others = [(start, bases[b]) for _, start, b in more]
            trials.append(t)
        trials.sort(key=lambda t: -t.score)
        return trials

    # ------------------------------------------------------------------------------------------
    def judge(self, M: Model, C: Model) -> tuple[float, float]:
        """``(validation ratio C / M, t)``: ``t`` is the larger of two paired t-statistics over the
        validation segments, of the errors' differences and of their log-ratios.

        The differences are dominated by the segments the current model misses most -- an effect
        that fixes those consistently is real even if it costs a little where nothing was wrong
        (EMPS: Coulomb friction is worse on the one segment at rest). The log-ratios weigh every
        segment alike and catch an effect that helps consistently everywhere by modest amounts;
        ``KAPPA`` residuals' worth of noise is added to both errors so that a segment already
        within the data's precision cannot vote with the ratio of two tiny numbers, and a segment
        both models predict within ``TIE`` of that is left out of both tests (``_judge``).
        """
        return self._judge(M, M.val, C.val)

    def _judge(self, M: Model, a, b) -> tuple[float, float]:
        a, b = np.asarray(a), np.asarray(b)
        ratio = float(np.sum(b) / max(np.sum(a), 1e-300))
        floor = KAPPA * max(M.result.n / max(len(self.fit_tiles), 1), 1.0)
        # a segment both models predict within ``TIE`` of that floor is a tie: it tells neither
        # way, and kept it only dilutes the segments that do (a 3 s PRBS recording, 7 of its 10
        # validation segments at rest: a delay predicting the other 3 near perfectly had t = 1.99)
        told = np.maximum(a, b) > TIE * floor
        if told.sum() >= 3:
            a, b = a[told], b[told]
        return ratio, max(_paired_t(a - b), _paired_t(np.log((a + floor) / (b + floor))))

    def level(self, M: Model, val=None) -> float:
        """How much ``M`` misfits, per residual (1: by the data's precision): the larger of its
        validation objective and its fitted segments' own (the data part of the fit's objective);
        with ``val`` (its per-segment validation values at another step) that alone.

        The fitted segments count too because a recording need not be alike throughout: a
        policy's episode swings up, then balances, and its validation tail (the balancing) can
        sit far below the floors while the fitted segments (the swings) are missed by far more
        (the pendulum of ``benchmarks/closed_loop.py``: after its friction, 0.0015 per residual on
        the tail, 30-70 on the swings; a 6-sample delay with t = 44 was stopped by the floor).
        On the 216 cases of the independent benchmark's two tuning lists (recordings alike
        throughout) it is the larger in 36% of the trials, mostly by a little, and no answer
        changed (``tuning.md`` step 34)."""
        n = max(M.result.n / max(len(self.fit_tiles), 1), 1) * len(self.val_tiles)
        lv = float(np.sum(M.val if val is None else val) / n)
        return lv if val is not None else max(lv, float(M.result.sse) / max(M.result.n, 1))

    def _passes(self, ratio, t, level=float("inf"), first=False, step_level=None) -> bool:
        """The test of a model against the one it extends (``first``: that one has no effect);
        ``step_level``: the physics step's floor (default: the diagnosis' own step's)."""
        c = self.cfg
        return ratio <= 1 - self.gain_asked(first) and t >= c.min_t and (level > self._floor(step_level) or ratio <= c.strong)

    def gain_asked(self, first: bool) -> float:
        """The relative drop of the validation error an effect must bring: ``min_gain_first`` on a
        model with no effect, ``min_gain`` on one with effects."""
        return self.cfg.min_gain_first if first else self.cfg.min_gain

    def _floor(self, step_level=None) -> float:
        """The misfit a model must exceed for an effect on it to be trusted (``floor_level``,
        ``floor_step``), at the diagnosis' own step or at one whose floor is ``step_level``."""
        c = self.cfg
        return max(c.floor_level, c.floor_step * (self.step_level if step_level is None else step_level))

    def _accept(self, M: Model, C: Model, first: bool) -> tuple[bool, float, float, str]:
        """Does ``C`` pass against ``M``? ``(passed, ratio, t, note)``, the note saying when it took
        the finer step's check (``_finer_passes``)."""
        ratio, t = self.judge(M, C)
        level = self.level(M)
        if not C.result.phi < M.result.phi:
            return False, ratio, t, ""
        if self._passes(ratio, t, level, first):
            if (short := self._within_one_step(M, C)) and self.cfg.finer >= 2 and self._finer is not None:
                ok, note = self._finer_passes(M, C, first, short)
                return ok, ratio, t, note
            return True, ratio, t, ""
        if self._passes(ratio, t, level, first, step_level=0.0):  # blocked by the step's floor alone
            ok, note = self._finer_passes(M, C, first)
            return ok, ratio, t, note
        return False, ratio, t, ""

    def failed_t_alone(self, M: Model, tr: Trial) -> bool:
        """``tr``, fitted on top of ``M``, failed the t-test and nothing else: it lowered the
        validation error by the gain asked, on a model that misfits by more than the floors (at
        its own step: one judged at the finer step is not), fitted the training segments better,
        and away from its absent value. One stopped by the floors is not: there ``M`` already
        predicts within the precision of the data and of the physics step, and a ratio of two
        such errors is no evidence. (The report lists such candidates as unconfirmed,
        ``diagnose._unconfirmed``.)"""
        C = tr.model
        return (C is not None and not tr.passed and not tr.finer and np.isfinite(tr.t) and tr.t < self.cfg.min_t
                and not self._absent(tr.candidate, C) and C.result.phi < M.result.phi
                and self._passes(tr.val_ratio, np.inf, self.level(M), not M.effects))

    def _within_one_step(self, M: Model, C: Model) -> str:
        """Why ``C`` is judged against ``M`` at the ``finer`` step too, whatever the floors say (""
        if not): an effect ``C`` adds is a delay or a lag shorter than one physics step. An
        integrator shifts what it simulates by a fraction of its step (semi-implicit Euler's phase
        error is about half of one), so a timing effect that small may be that shift taken up, on
        data precise enough to show it (the independent benchmark's extra list: a 0.4 ms delay at
        1 ms steps named beside a sensor offset on noiseless 1 kHz data, ``tuning.md`` step 35)."""
        h = self.f.sh.sys.h
        have = {e.label for e in M.effects}
        for c in C.effects:
            if c.label in have or c.effect not in TIMING:
                continue
            v = float(C.z[self.spec.index(c.params[0])])
            seconds = v * self.f.sh.dt if c.effect == "action_delay" else v  # the delay is in samples
            if 0.0 < seconds < h:
                kind = "delay" if c.effect == "action_delay" else "lag"
                return f"a {kind} of {seconds * 1e3:.3g} ms, shorter than the {h * 1e3:.3g} ms physics step"
        return ""

    def _finer_passes(self, M: Model, C: Model, first: bool, why: str = "") -> tuple[bool, str]:
        """``C`` lowers the validation error of a model ``M`` that already misfits by no more than
        the physics step alone causes: the gain may be the integrator's error taken up (a damping
        for its numerical dissipation, a lag for its phase). Both are simulated again with a step
        ``finer`` times shorter, where that error is mostly gone: an effect that only absorbed it
        now over-corrects and loses its gain; a real one keeps it (``SelectConfig.finer``)."""
        k = self.cfg.finer
        if k < 2 or self._finer is None:
            return False, ""
        if self._fine is _UNBUILT:
            self.progress(f"building the simulator at a {k}x finer physics step")
            self._fine = self._finer(k)   # None where none can be built
        f2 = self._fine
        if f2 is None:
            return False, ""
        zs = [self._fitted_finer(f2, X) for X in (M, C)]
        out = f2.velocities_many(zs, [f2.v_hat] * 2, self.val_tiles)
        a, b = out[0][1], out[1][1]
        ratio, t = self._judge(M, a, b)
        level, own = self.level(M, a), self.level(M, M.val)
        # the gain kept at the finer step is the evidence: its own measured floor is not asked
        # again (``SelectConfig.finer``); the absolute floor is, and most of the gain must stay
        ok = self._passes(ratio, t, level, first, step_level=0.0) and ratio <= self.cfg.finer_ratio
        why = why or (f"its base misfits by less than the physics step alone causes ({self.level(M):.3g} per residual, "
                      f"floor {self._floor():.3g})")
        return ok, (f"{why}; at a {k}x finer step: ratio {ratio:.3f}, t = {t:.1f}, "
                    f"misfit {level:.3g} ({own:.3g} at its own step) against the floor "
                    f"{self._floor(0.0):.3g}: {'passes' if ok else 'fails'}")

    def _fitted_finer(self, f2, X: Model) -> np.ndarray:
        """``X``'s parameters re-fitted at the finer step (``SelectConfig.finer_refit`` steps from
        its own; the model a round extends is fitted there once)."""
        if self.cfg.finer_refit <= 0:
            return X.z
        hit = self._fine_fits.get(id(X))
        if hit is None or hit[0] is not f2:
            res = self._fit_with(f2, X.effects, X.z, X.result.v0, X.params, self.cfg.finer_refit)
            hit = self._fine_fits[id(X)] = (f2, X, res.z)   # (X kept: its id is not reused while cached)
        return hit[2]

    def _try(self, M: Model, trial: Trial) -> Trial:
        """Fit the candidate on top of ``M`` (validation comes later, batched: ``_judge_all``)."""
        c = trial.candidate

        def fit_from(start, base, cand=c):
            z0 = base[0].copy()
            z0[self.spec.indices(list(cand.params))] = np.clip(start, [r[0] for r in cand.search],
                                                               [r[1] for r in cand.search])
            return self.fit(M.effects + [cand], z0, base[1])

        C = fit_from(trial.start, getattr(trial, "base", (M.z, M.result.v0)))
        for start, base in trial.others:  # other widths of the grid: the band's fit is local
            C1 = fit_from(start, base)
            if C1.result.phi < C.result.phi:
                C = C1
        timing = [e for e in M.effects if e.effect in TIMING]
        if timing and self.cfg.timing_restart > 0 and c.effect not in TIMING:
            z, i = M.z.copy(), self.spec.indices([e.params[0] for e in timing])
            z[i] = np.maximum(self.cfg.timing_restart * z[i], [e.search[0][0] for e in timing])
            C1 = fit_from(trial.start, (z, M.result.v0))
            if C1.result.phi < (1 - RESTART_MARGIN) * C.result.phi:
                trial.note = (f"fitted from {self.cfg.timing_restart:g}x the model's {', '.join(e.label for e in timing)}"
                              f" (training objective {C1.result.phi / C.result.phi:.3g} of the fit from its own)")
                C = C1
        if c.effect == "backlash" and self.cfg.band_scan:
            C = self._scan_width(M, c, C)
        # a fit that ends at the edge of the searched range: widen once and fit again
        v = float(C.z[self.spec.index(c.params[0])])
        if _at_edge(c, v):
            wide = c.widen()
            C2 = self.fit(M.effects + [wide], C.z.copy(), C.result.v0)
            if c.effect == "actuator_saturation":  # a limit far below: the fit from the edge stays there
                for g in wide.grid:
                    C3 = fit_from(g, (C.z, C.result.v0), wide)
                    if C3.result.phi < C2.result.phi:
                        C2 = C3
            trial.note = "; ".join(x for x in (trial.note, f"{c.params[0]} ended at the edge of its range ({v:.4g}); "
                                                           "searched wider") if x)
            if C2.result.phi < C.result.phi:
                C, trial.candidate = C2, wide
            v2 = float(C.z[self.spec.index(trial.candidate.params[0])])
            if _at_edge(trial.candidate, v2):
                trial.note += f"; still at the edge after widening ({v2:.4g}): the value is a bound, not an estimate"
        trial.model = C
        return trial

    def _scan_width(self, M: Model, c: Candidate, C: Model) -> Model:
        """The band's fit moved on from the best width of a fine scan: ``band_scan`` widths over
        the searched range, the fit's other parameters and start velocities held, simulated
        together; when one predicts the fitted segments better, the fit is run again from it."""
        i = self.spec.index(c.params[0])
        widths = np.geomspace(c.search[0][0], c.search[0][1], self.cfg.band_scan)
        zs = np.repeat(C.z[None], len(widths), 0)
        zs[:, i] = widths
        r = self.f.residuals(zs, np.repeat(C.result.v0[None], len(widths), 0), self.fit_tiles)
        phis = [self.f.phi(rr, C.result.v0, self.fit_tiles) for rr in r]
        k = int(np.argmin(phis))
        if phis[k] < C.result.phi:
            C2 = self.fit(M.effects + [c], zs[k], C.result.v0)
            if C2.result.phi < C.result.phi:
                return C2
        return C

    def _judge_all(self, M: Model, trials: list[Trial]) -> None:
        self.validate([t.model for t in trials])
        level = self.level(M)
        for t in trials:
            t.passed, t.val_ratio, t.t, note = self._accept(M, t.model, not M.effects)
            t.base_level = level
            t.finer = bool(note)
            if note:
                t.note = (t.note + "; " if t.note else "") + note
            c = t.candidate
            if (t.passed and c.effect == "backlash" and self.cfg.band_shown
                    and c.at_bottom(float(t.model.z[self.spec.index(c.params[0])]))):
                self._band_shown(t)

    def _band_shown(self, trial: Trial) -> None:
        """Fails a passing backlash, fitted at the bottom of its width's range, whose band the data
        do not show: fitted again with the band closed (its width a thousandth of that bottom; the
        motor side kept), the band must pass against that fit as an effect passes against its
        base (``SelectConfig.band_shown``)."""
        C, c = trial.model, trial.candidate
        width = c.params[0]
        z0 = C.z.copy()
        z0[self.spec.index(width)] = 1e-3 * c.search[0][0]
        closed = self.fit(C.effects, z0, C.result.v0, hold=(width,))
        self.validate([closed])
        ratio, t = self._judge(closed, closed.val, C.val)
        ok = closed.result.phi > C.result.phi and self._passes(ratio, t)
        trial.passed = ok
        why = f"against its band closed (the motor side kept): ratio {ratio:.3f}, t = {t:.1f}"
        trial.note = "; ".join(x for x in (trial.note, why if ok else why + ": the band is not shown") if x)

    def _asymmetry(self, M: Model, trial: Trial) -> Trial:
        """Coulomb friction with a level per direction, kept if it passes against the symmetric fit."""
        c = trial.candidate
        jn = c.target
        name = f"coulomb_asym:{jn}"
        if self.allowed is not None and name not in self.allowed:
            return trial
        asym = dataclasses.replace(c, params=c.params + (name,), grid=(c.grid[0] + (0.0,),),
                                   scales=c.scales + (0.3,), search=c.search + ((-0.95, 0.95),))
        C = self.fit(M.effects + [asym], trial.model.z, trial.model.result.v0)
        self.validate([C])
        ratio, t = self.judge(trial.model, C)
        if self._passes(ratio, t, self.level(trial.model)):
            base_ratio, base_t = self.judge(M, C)
            return dataclasses.replace(trial, candidate=asym, model=C, val_ratio=base_ratio, t=base_t,
                                       note=(trial.note + "; " if trial.note else "") +
                                       f"a level per direction: validation error {ratio:.3f} of the symmetric fit's")
        return trial

    def _absent(self, c: Candidate, M: Model) -> bool:
        """``c`` ended at its absent value in the fitted model ``M`` (``Candidate.is_off``)."""
        return c.is_off(float(M.z[self.spec.index(c.params[0])]))

    def _absent_effect_gain(self, M: Model, tried: list[Trial]) -> Model | None:
        """A trial whose effect was fitted at its absent value (``Candidate.is_off``) cannot name
        it: its gain is the other parameters', a better optimum of ``M``'s own hypothesis that
        the fit of ``M`` missed. Such trials fail; the best of them that beats ``M`` on the
        fitting and validation data is re-fitted without the effect and returned (once per
        model: a refit is not searched again)."""
        best = None
        for t in tried:
            c = t.candidate
            if t.model is None or not self._absent(c, t.model):
                continue
            t.passed = False
            t.note = (t.note + "; " if t.note else "") + "fitted at its absent value: the gain is the other parameters'"
            if (not M.refined and t.model.result.phi < M.result.phi
                    and np.sum(t.model.val) < np.sum(M.val) and (best is None or np.sum(t.model.val) < np.sum(best.val))):
                best = t.model
        if best is None:
            return None
        R = self.fit(M.effects, best.z.copy(), best.result.v0)
        self.validate([R])
        if not (R.result.phi < M.result.phi and np.sum(R.val) < np.sum(M.val)):
            return None
        R.refined = True
        self.refits.append(f"{M.label} was re-fitted from the start a trial found (validation error "
                           f"{np.sum(R.val) / np.sum(M.val):.3f} of the first fit's)")
        self.progress(f"{M.label} re-fitted from a better start")
        return R

    def _pair(self, M: Model, tried: list[Trial]) -> tuple[Trial, Trial] | None:
        """When no single effect passes but one lowers the validation error (not consistently
        enough: a saturation that fixes the segments where it bites and costs where a missing
        delay matters), or one's fit takes up more than ``PAIR_TRAIN`` of the training objective
        however it validates, every two of the fitted ones (``top``: up to 6 pairs) are fitted together;
        a candidate that alone predicts worse may be half of the answer (tuning half: a joint
        stiffness that only helps beside a sensor offset, the fourth of four alone). So are the
        best fit and each of the ``pair_screen`` candidates that screen best on top of it, of
        those not fitted alone (a half the other's misfit hid from the first screen), and so on
        top of the fit with the lowest training objective where that is another. The
        pair joins the model if it passes the same test against ``M`` and lowers the validation
        error by ``min_gain`` below each of its members alone. Only on the nominal model: on top
        of a named effect the data are mostly explained, and more pairs tested on the same
        validation segments would name a false pair (tuning half: a stiffness + backlash beside a
        saturation). Returns ``(first, second)``: the first's single fit and the pair as the
        second's trial, or None."""
        c = self.cfg
        good = sorted([t for t in tried if t.model is not None and t.model.result.phi < M.result.phi],
                      key=lambda t: t.val_ratio)
        # a candidate that takes up most of the training misfit yet predicts the validation segments
        # worse is half of an answer too: the combos list's 6072, a cart-pole's 16.5 ms delay
        # (training objective 0.07 of the nominal re-fit's, validation 4.3x worse) beside a rail
        # friction as large as the push, under which the cart coasts in one recording's tail
        if not good or (good[0].val_ratio > 1 - c.min_gain and good_fit(good, M) > PAIR_TRAIN):
            return None
        level = self.level(M)
        # (first, second, where the second's parameters start, the lower validation error alone)
        pairs = [(a, b, b.model.z, min(np.sum(a.model.val), np.sum(b.model.val)), "")
                 for i, a in enumerate(good) for b in good[i + 1:] if a.candidate.label != b.candidate.label]
        if c.pair_screen:
            # the other half of a pair may screen low on the nominal model, where the first half's
            # misfit hides it, and so never be fitted (the combos list's 6110: a flywheel's delay
            # fitted, its friction screened sixth of seven): screened on top of the best fit, the
            # best ``pair_screen`` not fitted alone are paired with it, from their screen's starts.
            # So on top of the fit that takes up the most of the training misfit, where that is
            # another: the half whose other half is missing validates worse than it fits (the
            # combos list's 6099: a force limit at 0.36 of the training objective, validating
            # 2.6x worse, beside a delay screened at -0.002 on the nominal model)
            fitted = {t.candidate.label for t in tried}   # (``M`` is the nominal model: nothing named yet)
            rest = [x for x in self.cands if x.label not in fitted]
            most = min(good, key=lambda t: t.model.result.phi)
            for a in [good[0]] + ([most] if most is not good[0] else []):
                self.progress(f"screening {len(rest)} candidates on top of {a.candidate.label} for a pair")
                for x in [t for t in self.screen(a.model, rest) if t.score >= c.min_score][: c.pair_screen]:
                    z = a.model.z.copy()
                    z[self.spec.indices(list(x.candidate.params))] = x.start
                    pairs.append((a, x, z, np.sum(a.model.val), " (screened on top of its fit)"))
        best = None
        for a, b, zb, alone, how in pairs:
            self.progress(f"fitting {a.candidate.label} and {b.candidate.label} together on top of {M.label}")
            z0 = a.model.z.copy()
            idx = self.spec.indices(list(b.candidate.params))
            z0[idx] = zb[idx]
            P = self.fit(M.effects + [a.candidate, b.candidate], z0, a.model.result.v0)
            self.validate([P])
            # the cheap conditions first: ``_accept`` may simulate at a finer step
            if (np.sum(P.val) <= (1 - c.min_gain) * alone
                    and not any(self._absent(x.candidate, P) for x in (a, b))
                    and (best is None or np.sum(P.val) < np.sum(best[2].val))
                    and (acc := self._accept(M, P, False))[0]):
                best = (a, b, P, acc[1], acc[2], acc[3], how)
        if best is None:
            return None
        a, b, P, ratio, t, note, how = best
        second = Trial(b.candidate, b.score, P, ratio, t, True, level,
                       note=f"fitted together with {a.candidate.label}{how}: neither passed alone" + (f"; {note}" if note else ""))
        return a, second

    def _group(self, M: Model, trials: list[Trial]):
        """Each effect of ``SelectConfig.group`` offered on two or more joints (or actuators),
        fitted on all of them at once on top of ``M`` (the nominal model, where nothing passed
        alone or in a pair), each member from its screen's start; members fitted at their absent
        value are left out and the rest fitted again. The group joins if it passes the same test
        against ``M`` (``_accept``). Returns ``(the model, its forward path from M (a fit of each
        prefix), a round per member after the first)`` or None. The backward check then judges
        each member against the others (``_prune``): a joint that does not rub is dropped there."""
        order = {c.label: i for i, c in enumerate(self.cands)}
        for effect in self.cfg.group:
            members = sorted([t for t in trials if t.candidate.effect == effect], key=lambda t: order[t.candidate.label])
            if len(members) < 2:
                continue
            z0 = M.z.copy()
            for t in members:  # (from its screen's start: a joint's own fit may have taken up the others')
                z0[self.spec.indices(list(t.candidate.params))] = t.start
            cands = [t.candidate for t in members]
            self.progress(f"fitting {effect} on {len(cands)} joints together on top of {M.label}")
            G = self.fit(M.effects + cands, z0, M.result.v0)
            absent = [c for c in cands if self._absent(c, G)]
            if absent:
                cands = [c for c in cands if c not in absent]
                if len(cands) < 2:
                    continue
                G = self.fit(M.effects + cands, self._neutral(G.z, absent), G.result.v0)
            self.validate([G])
            ok, ratio, t, note = self._accept(M, G, False)
            if not ok:
                continue
            path = self._path(G, [M])
            level = self.level(M)
            rows = []
            for k in range(2, len(path)):
                r, tk = self.judge(path[k - 1], path[k]) if k < len(path) - 1 else (ratio, t)
                c = path[k].effects[-1]
                rows.append([Trial(c, next(x.score for x in members if x.candidate is c), path[k], r, tk, True, level,
                                   note=f"fitted with {effect} on {', '.join(x.target for x in cands)} at once: no joint's "
                                        f"alone passed (together: validation ratio {ratio:.3f}, t = {t:.1f})"
                                        + (f"; {note}" if note else ""))])
            return G, path, rows
        return None

    def run(self) -> tuple[Model, list[Model]]:
        """Forward selection; returns the final model and the models after each step (``none`` first)."""
        self.progress("re-fitting the nominal parameters (none)")
        M = self.none()
        steps = [M]
        remaining = list(self.cands)
        while len(M.effects) < self.cfg.max_effects and remaining:
            self.progress(f"screening {len(remaining)} candidates on top of {M.label}")
            trials = self.screen(M, remaining)
            tried = []
            chosen = [t for t in trials if t.score >= self.cfg.min_score][: self.cfg.top]
            for tr in chosen + self._geared(M, trials, chosen):
                self.progress(f"fitting {tr.candidate.label} on top of {M.label}")
                tried.append(self._try(M, tr))
            self._judge_all(M, tried)
            self.rounds.append(trials)
            better = self._absent_effect_gain(M, tried)
            if better is not None:  # the same hypothesis, fitted better: the round again from there
                self.rounds.pop()
                M = steps[-1] = better
                continue
            passed = [t for t in tried if t.passed]
            if not passed and not M.effects and self.cfg.max_effects >= 2:
                pair = self._pair(M, tried)
                if pair is not None:  # two effects that only together explain the data
                    first, second = pair
                    self.units.append(frozenset({first.candidate.label, second.candidate.label}))
                    steps.append(first.model)
                    self.rounds.append([second])
                    M = second.model
                    steps.append(M)
                    done = {first.candidate.label, second.candidate.label}
                    remaining = [c for c in remaining if c.label not in done]
                    continue
                group = self._group(M, trials)
                if group is not None:  # one effect on every joint, no joint's alone enough
                    G, path, rows = group
                    self.groups.append(frozenset(c.label for c in G.effects))
                    self.rounds += rows
                    steps += path[1:]
                    M = G
                    done = {c.label for c in G.effects}
                    remaining = [c for c in remaining if c.label not in done]
                    continue
            if not passed:
                break
            passed = [self._at_model_masses(M, t) for t in passed]
            best = self.best(passed)
            if best.candidate.effect == "coulomb_friction":
                best = self._asymmetry(M, best)
            M = best.model
            steps.append(M)
            remaining = [c for c in remaining if c.label != best.candidate.label]
        if self.cfg.swap:
            M, steps = self._swap(M, steps)
        if self.cfg.shared_lag and self.shared is not None:
            M, steps = self._shared_lag(M, steps)
        if self.cfg.rotor and self.rotors:
            M, steps = self._rotor(M, steps)
        return self._prune(M, steps)

    def _shared_lag(self, M: Model, steps: list[Model]) -> tuple[Model, list[Model]]:
        """The shared lag (``self.shared``) in place of ``M``'s action delay (``SelectConfig.shared_lag``)."""
        delay = next((c for c in M.effects if c.effect == "action_delay"), None)
        if delay is None:
            return M, steps
        return self._in_place(M, steps, delay, self.shared, "one lag shared by every actuator, as identical "
                              "drives have", "the delay")

    def _rotor(self, M: Model, steps: list[Model]) -> tuple[Model, list[Model]]:
        """Each band ``M`` names on an actuator of ``self.rotors`` in turn, the rotor inertia of the
        joint it drives in its place where its validation ratio is at most ``SelectConfig.rotor_ratio``."""
        for band in [c for c in M.effects if c.effect == "backlash" and c.target in self.rotors]:
            M, steps = self._in_place(M, steps, band, self.rotors[band.target], "a rotor's inertia on the joint "
                                      "the band's actuator drives: its motor-side inertia may be all the band "
                                      "explains", f"the band {band.label}", self.cfg.rotor_ratio)
        return M, steps

    def _in_place(self, M: Model, steps: list[Model], old: Candidate, new: Candidate, why: str,
                  words: str, max_ratio: float = np.inf) -> tuple[Model, list[Model]]:
        """``new`` fitted in place of ``M``'s named ``old``, replacing it where it passes the test
        against ``M`` (``_accept``) at a validation ratio of at most ``max_ratio``, ``steps`` then
        rebuilt (``_path``); a note either way (``why``: what ``new`` stands for; ``words``: how
        the note names ``old``)."""
        self.progress(f"fitting {new.label} in place of {old.label}")
        R = self._without(M, old)
        tr = self._try(R, self.screen(R, [new])[0])
        C = tr.model
        self.validate([C])
        ok, ratio, t, _ = self._accept(M, C, False)
        replaced = ok and ratio <= max_ratio
        kept = f"{words} kept" + (f" (it passes, but the ratio asked is {max_ratio:g} or less)" if ok else "")
        self.refits.append(f"{new.label} ({why}) fitted in place of {words}: validation ratio {ratio:.3f}, "
                           f"t = {t:.1f}, " + (f"it replaced {words}" if replaced else kept))
        if not replaced:
            return M, steps
        return C, self._path(C, steps)

    def _swap(self, M: Model, steps: list[Model]) -> tuple[Model, list[Model]]:
        """Sequential replacement (``SelectConfig.swap``): each named effect of ``M`` in turn is
        taken out, the candidates not named are screened on top of the rest (re-fitted), and the
        best scoring at least ``min_score`` is fitted there; it replaces the effect where that
        model passes the test against ``M`` (``_accept``). ``steps`` is then rebuilt as the
        forward path of the effects named (``_path``); the backward check follows."""
        if len(M.effects) < 2:
            return M, steps
        start = M
        for c in list(M.effects):
            if not any(e is c for e in M.effects):   # (replaced already: a replacement keeps the others' objects)
                continue
            R = self._without(M, c)
            named = {e.label for e in M.effects}
            rest = [x for x in self.cands if x.label not in named]
            self.progress(f"screening {len(rest)} candidates in place of {c.label}")
            for tr in [t for t in self.screen(R, rest) if t.score >= self.cfg.min_score][:1]:
                tr = self._try(R, tr)
                C = tr.model
                self.validate([C])
                ok, ratio, t, _ = self._accept(M, C, False)
                if ok:
                    self.refits.append(f"{tr.candidate.label} replaced {c.label} (validation ratio {ratio:.3f}, t = {t:.1f})")
                    M = C
        if M is start:
            return M, steps
        return M, self._path(M, steps)

    def _path(self, M: Model, steps: list[Model]) -> list[Model]:
        """The forward path of ``M``'s effects: the recorded ``steps`` while they are prefixes of
        it, then fits of ``M`` without its later effects."""
        path = [steps[0]]
        for k in range(1, len(M.effects) + 1):
            want = [c.label for c in M.effects[:k]]
            have = next((S for S in steps if [c.label for c in S.effects] == want), None)
            if have is None:
                have = M if k == len(M.effects) else self._without_all(M, M.effects[k:])
            path.append(have)
        return path

    def _geared(self, M: Model, trials: list[Trial], chosen: list[Trial]) -> list[Trial]:
        """The backlash trials on the actuators of joints where ``M`` has a Coulomb friction, not
        among ``chosen`` (``SelectConfig.geared``): fitted whatever their screen score."""
        if not self.cfg.geared:
            return []
        sysm = self.f.sh.sys
        rubbing = {c.target for c in M.effects if c.effect == "coulomb_friction"}
        have = {t.candidate.label for t in chosen}
        out = []
        for t in trials:
            c = t.candidate
            if c.effect != "backlash" or c.label in have or not np.isfinite(t.score):
                continue
            j = actuator_joint(sysm.mj, sysm.actuators.index(c.target))
            if j >= 0 and sysm.joints[j] in rubbing:
                out.append(t)
        return out

    def best(self, passed: list[Trial]) -> Trial:
        """Of the candidates that passed, the one that predicts all the training data best (the
        validation tail alone can be too short to rank two that both explain it), but of a delay
        and a lag the one whose fitted and validation errors have the lower product
        (``SelectConfig.timing_relative``); with plausible masses first
        (``SelectConfig.plausible_masses``)."""
        plausible = [t for t in passed if not self.far_masses(t.model)] if self.cfg.plausible_masses else []
        pool = plausible or passed
        best = min(pool, key=lambda t: t.model.result.phi + np.sum(t.model.val))
        # A delay and a lag shape the command alike with one parameter each. Where both pass, the
        # sum of the two errors is mostly the fitted segments' (70% of the data, and fitted to),
        # and 2% there outweighs a validation that prefers the other by 4-13%; the product
        # weighs the two relative differences alike (tuning lists, every round where one of the
        # two was true: 3 true delays gained, 6115, 6119, 3913, none lost; over every kind of
        # candidate, it also lost 6138's stiffness to a payload; ``tuning.md`` step 83)
        if self.cfg.timing_relative and best.candidate.effect in TIMING:
            def product(t):
                return np.log(max(t.model.result.phi, 1e-300)) + np.log(max(float(np.sum(t.model.val)), 1e-300))
            best = min([best] + [t for t in pool if t.candidate.effect in TIMING], key=product)
        return best

    def _at_model_masses(self, M: Model, trial: Trial) -> Trial:
        """A passing candidate whose fit needs a body mass ``FAR_MASS`` times off, fitted again with
        every mass held at the current model's (at the model file's where that one is far too);
        where that fit passes as well, it replaces the first (``SelectConfig.plausible_masses``).

        An effect can make a direction of the fit nearly free: a servo held at its force limit
        most of the time moves as ``m a + c v = +-L``, which every common scale of mass, damping
        and limit leaves unchanged, and the fit slides along it (the beside list's 3834: a 23 N
        limit fitted at 320 N beside a 70 kg carriage of 5 kg). Judged with that mass, the right
        effect lost to a worse one with plausible masses."""
        C = trial.model
        far_names = self.far_masses(C) if self.cfg.plausible_masses and trial.passed else []
        if not far_names:
            return trial
        masses = [n for n in C.params if n.startswith("mass:")]
        z0 = C.z.copy()
        for n in masses:
            i, nominal = self.spec.index(n), float(self.spec[n].default)
            z0[i] = nominal if is_far_mass(nominal, float(M.z[i])) else M.z[i]
        # start where that scale symmetry puts the fit at these masses: every force and inertia
        # scaled with them (the far masses' common factor; ``Fitter.fit`` brings a start scaled
        # past its range back inside)
        far = self.spec.indices(far_names)
        k = float(np.exp(np.mean(np.log(z0[far] / C.z[far]))))
        for n in C.params:
            p = self.spec[n]
            if n not in masses and (p.unit.startswith("N") or p.unit.startswith("kg")):
                z0[self.spec.index(n)] = C.z[self.spec.index(n)] * k
        C2 = self.fit(C.effects, z0, C.result.v0, hold=tuple(masses))
        self.validate([C2])
        passed, ratio, t, note = self._accept(M, C2, not M.effects)
        if not passed:
            return trial
        first = ", ".join(f"{n} = {float(C.z[self.spec.index(n)]):.4g}" for n in far_names)
        trial.model, trial.val_ratio, trial.t = C2, ratio, t  # (in place: the round's record shows this fit)
        trial.note = "; ".join(x for x in (trial.note, note, f"fitted again with the masses held at the model's "
                                           f"(the first fit needed {first}: forces and masses scaled together)") if x)
        return trial

    def far_masses(self, M: Model) -> list[str]:
        """The body masses ``M`` re-fitted more than ``FAR_MASS`` times off the model's."""
        return [n for n in M.params if n.startswith("mass:")
                and is_far_mass(float(self.spec[n].default), float(M.z[self.spec.index(n)]))]

    def _neutral(self, z: np.ndarray, drop: list[Candidate]) -> np.ndarray:
        """A copy of ``z`` with the parameters of the effects ``drop`` back at their neutral values."""
        z = z.copy()
        idx = self.spec.indices([p for c in drop for p in c.params])
        z[idx] = self.spec.default[idx]
        return z

    def _without(self, M: Model, c: Candidate) -> Model:
        """``M`` re-fitted without effect ``c`` (its parameters back at their neutral values), not
        validated: the swap only screens and fits on it (``_without_all`` validates what it returns).

        The fit is a function of ``M`` and ``c`` alone, and the swap, the rotor's trial in place of
        a band and the backward check each ask for it of the same final model: it is made once
        (the same numbers; a 3-link arm's diagnosis made 27 of its 434 simulator calls twice)."""
        key = (id(M), id(c))
        if key not in self._dropped:  # (M and c kept with it: their ids stay theirs)
            self._dropped[key] = (M, c, self.fit([e for e in M.effects if e is not c], self._neutral(M.z, [c]),
                                                 M.result.v0))
        return self._dropped[key][2]

    def _units(self, M: Model) -> list[list[Candidate]]:
        """``M``'s effects as the backward check judges them: one by one, except a pair that
        joined together (``_pair``: neither passed alone), which stays one unit while both are in."""
        out, seen = [], set()
        for c in M.effects:
            if c.label in seen:
                continue
            unit = [c]
            for u in self.units:
                if c.label in u:
                    unit = [e for e in M.effects if e.label in u]
                    break
            unit = unit if len(unit) == 2 else [c]
            seen.update(e.label for e in unit)
            out.append(unit)
        return out

    def _prune(self, M: Model, steps: list[Model]) -> tuple[Model, list[Model]]:
        """Backward elimination: every named effect must still pass the test against the model
        without it, the others in place. An effect found early can lose its reason once a later
        one is in (a motor lag that stood in for a delay; a friction that made up for a lag
        fitted at a local minimum). The weakest one that fails is dropped and the rest re-fitted,
        until all pass; ``steps`` is then rebuilt as the forward path of the effects that stay.

        A pair that joined together is judged as one (``_units``): against the model without
        both. Each member alone already failed on the nominal model -- that is why the pair was
        fitted -- so judging one against the other would undo that finding, not check it (tuning
        half, 138: a friction and a delay on a pendubot, validation ratio 0.034 together, t = 7.4;
        the delay then dropped for t = 1.9 against the friction alone at ratio 0.038, and the
        friction alone predicted the held-out data worse: nothing named)."""
        if len(M.effects) < 2:
            return M, steps
        start = M
        while len(M.effects) >= 2:
            self.progress(f"checking that each effect of {M.label} is still needed")
            worst = None
            for unit in self._units(M):
                R = self._without_all(M, unit)
                ok, ratio, t, _ = self._accept(R, M, not R.effects)
                if not ok and self._carries_fit(M, R, unit, ratio, t):
                    continue
                if not ok and (worst is None or ratio > worst[1]):
                    worst = (unit, ratio, t, R)
            if worst is None:
                break
            unit, ratio, t, M = worst
            two = len(unit) > 1
            what = " + ".join(c.label for c in unit) + (" were" if two else " was")
            self.pruned.append(f"{what} dropped: with {M.label if M.effects else 'no effect'} in the model "
                               f"{'they' if two else 'it'} no longer lower{'' if two else 's'} the validation error "
                               f"enough (ratio {ratio:.3f}, t = {t:.1f})")
        if M is start:
            return M, steps
        return M, self._path(M, steps)   # the forward path of what stays

    def _carries_fit(self, M: Model, R: Model, unit: list[Candidate], ratio: float, t: float) -> bool:
        """Does ``unit`` carry ``M``'s fit (``R``, ``M`` without it, fits the fitted segments more
        than ``prune_fit`` times worse)? Then the backward check keeps it, with a note."""
        k = self.cfg.prune_fit
        worse = R.result.phi / max(M.result.phi, 1e-300)
        if not k or worse <= k:
            return False
        note = (f"{' + '.join(c.label for c in unit)} kept although the validation segments alone would drop it "
                f"(ratio {ratio:.3f}, t = {t:.1f}): without it the fitted segments' error is {worse:.3g}x higher")
        if note not in self.pruned:
            self.pruned.append(note)
        return True

    def _without_all(self, M: Model, drop: list[Candidate]) -> Model:
        """``M`` re-fitted without the effects ``drop`` (one at a time, the last first), validated
        (the backward check judges it; the forward path keeps it)."""
        R = M
        for c in reversed(drop):
            R = self._without(R, c)
        self.validate([R])
        return R
