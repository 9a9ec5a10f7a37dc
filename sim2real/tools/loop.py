"""The sim-to-real loop: record the policy on the real system, diagnose, retrain on what was found.

One iteration (``iteration``), in ``out/iter_<k>/``:

1. ``recordings/``: ``episodes`` episodes of the current policy on the target (``record.from_run``, ``record.save``);
2. ``diagnosis/``: the env's own MJCF diagnosed on them (all but the last episode fit, the last
   one held out: ``sysid.diagnose``);
3. ``run/``: the training config retrained with ``dr.from_diagnosis`` = that diagnosis (the fitted
   physics, randomised over +- k std: ``algos/from_diagnosis.py``); with ``warm_start`` it
   fine-tunes the policy that made the recordings instead of training a new one.

A diagnosis the loop cannot train on (``unusable``: its answer is ``inconclusive``, or it re-fitted
a body mass more than ``FAR_MASS`` times off the model's, which then stands in for something else)
is not trained on when the user gave a ``fallback`` box: the run trains on that box instead, and
``loop.json`` says why. What makes such a diagnosis is too little data: the hopper's nominal
policy falls within 0.1 s on its real plant, and three such recordings gave masses 5-25x the
model's beside a delay where the plant has a lag (``benchmarks/closed_loop.py``). The next
iteration records the fallback's policy, which stays up longer, and diagnoses again.

A diagnosed delay whose box reaches past the env's delay line is trained with a longer line
(``env_options.max_delay``: ``from_diagnosis.delay_line``), where ``dr.from_diagnosis`` alone
would refuse it.

The training config is the same base for every iteration (each diagnosis replaces the last one's
physics rather than adding to it); each diagnosis is of the real system, so what the first one
missed the second may find in recordings of a policy that behaves differently.
"""
from __future__ import annotations

import dataclasses
import os

from sim2real.algos.base import DRConfig
from sim2real.envs.base import ASSETS
from sim2real.training.driver import TrainConfig


@dataclasses.dataclass
class LoopConfig:
    """``scripts/loop.py``'s own settings (every other ``key=value`` is the training config's, and
    ``diagnose.<key>=value`` a diagnosis option).

    Attributes:
      target: the "real" system, an MJCF stepped by native MuJoCo.
      out: the loop's folder (``nominal/``, ``iter_<k>/``, ``loop.json``).
      run: a trained run to start from (empty: the config is trained first, ``out/nominal``).
      iterations: record -> diagnose -> retrain rounds (>= 1).
      episodes: recorded episodes per iteration (>= 2: the last one is held out).
      seed: initial states of the recordings; noise: the target's position-sensor noise (m or rad).
      eval_episodes: episodes on the target that score each policy at the end (>= 1).
      deterministic: record the policy's mean action; overwrite: replace an earlier loop folder;
      until_end: record an episode the env would end (a fall) on to its full length
        (``record.native``): a policy that falls at once still records seconds of the plant;
      progress: progress bars.
      warm_start: each retraining starts from the policy that made its recordings (its parameters
        and observation statistics; a fresh optimiser) instead of from scratch, as a researcher
        fine-tunes the deployed policy. It keeps what that policy learnt where the diagnosed
        physics is harder to learn from scratch (the cart-pole swing-up against 3 N of stiction:
        ``benchmarks/closed_loop.py``).
      warm_std: with ``warm_start``, the retraining's action standard deviation restarts at this
        (UDR's ``algo_options.warm_std``; 0: the recorded policy's own). A policy trained to the
        end of its schedule explores little; at 0.61 (the network's initial std) the cart-pole's
        loop went from 432 to 635 (README, "Restarting exploration when fine-tuning").
      fallback: the randomisation an iteration trains on when its diagnosis is ``unusable``
        (``fallback.params=[...] fallback.low=[...] fallback.high=[...]``, as ``dr.*``); empty:
        it trains on the diagnosis anyway, with a warning.
    """
    target: str = ""
    out: str = ""
    run: str = ""
    iterations: int = 1
    episodes: int = 3
    seed: int = 0
    noise: float = 0.0
    eval_episodes: int = 64
    deterministic: bool = True
    until_end: bool = False
    overwrite: bool = False
    progress: bool = True
    warm_start: bool = False
    warm_std: float = 0.0
    fallback: DRConfig = DRConfig()

    def __post_init__(self):
        from sim2real.common.config import ConfigError

        if not self.target or not self.out:
            raise ConfigError("loop needs target=PATH.xml (the real system) and out=DIR")
        for k in ("iterations", "eval_episodes"):
            if getattr(self, k) < 1:
                raise ConfigError(f"{k}={getattr(self, k)}: must be a positive integer")
        if self.episodes < 2:
            raise ConfigError(f"episodes={self.episodes}: must be >= 2 (the last one is held out)")
        if self.warm_std and not self.warm_start:
            raise ConfigError(f"warm_std={self.warm_std}: restarts a warm start's exploration; set warm_start=true")
        if self.warm_std:  # its bounds are UDR's, which the retraining gets it as (checked now, not after training)
            from sim2real.algos.udr import UDRConfig

            try:
                UDRConfig(warm_start=self.out, warm_std=self.warm_std)
            except ValueError as e:
                raise ConfigError(str(e)) from None


def env_model_path(env) -> str:
    """The env's own MJCF (what the diagnosis must describe for ``dr.from_diagnosis``); ``env`` is
    an env or its class."""
    return os.path.join(ASSETS, env.xml)


def unusable(d: dict) -> str | None:
    """Why the loop should not train on diagnosis ``d`` (a ``diagnosis.json``), or None."""
    from sim2real.sysid.diagnose import far_mass_list

    if d["answer"] == "inconclusive":
        return "the diagnosis is inconclusive"
    far = far_mass_list(d["nominal_refit"])
    return f"the diagnosis re-fitted masses far from the model's: {', '.join(far)}" if far else None


def iteration(run_dir: str, base: TrainConfig, target: str, out: str, episodes: int = 3, seed: int = 0,
              run_seed: int = 0, noise: float = 0.0, deterministic: bool = True, diagnose_options=(),
              progress: bool = False, warm_start: bool = False, fallback: DRConfig | None = None,
              until_end: bool = False, warm_std: float = 0.0) -> dict:
    """One loop iteration from the policy of ``run_dir`` (seed ``run_seed``): ``diagnose`` then
    ``retrain``; returns what it did (``recordings``, ``diagnosis`` summary, ``run`` folder,
    ``real_return`` of the recorded episodes, ``trained_on``: ``diagnosis`` or ``fallback``, and
    ``why`` the diagnosis was not used)."""
    paths, what, d = diagnose(run_dir, base, target, out, episodes, seed, run_seed, noise, deterministic,
                              diagnose_options, progress, until_end)
    res, dr, why = retrain(run_dir, base, out, d, run_seed, progress, warm_start, fallback, warm_std)
    return {"recordings": paths, "real_return": what["mean_return"], "run": res["run_dir"],
            "trained_on": "diagnosis" if dr.from_diagnosis else "fallback", "why": why or "",
            "diagnosis": {"answer": d["answer"],
                          "selected": [{"effect": s["effect"], "target": s["target"], "params": s["params"]}
                                       for s in d["selected"]],
                          "fitted_params": d["fitted_params"], "heldout_nrmse": [d["fit"]["before"], d["fit"]["after"]]}}


def diagnose(run_dir: str, base: TrainConfig, target: str, out: str, episodes: int = 3, seed: int = 0,
             run_seed: int = 0, noise: float = 0.0, deterministic: bool = True, diagnose_options=(),
             progress: bool = False, until_end: bool = False) -> tuple[list[str], dict, dict]:
    """Steps 1-2 of an iteration: ``(recording paths, record summary, diagnosis.json)``, written
    under ``out``; ``until_end``: ``LoopConfig.until_end``."""
    from sim2real.algos import from_diagnosis
    from sim2real.common import config as config_lib
    from sim2real.envs import make
    from sim2real.envs.registry import env_class
    from sim2real.tools.record import from_run, save
    from sim2real.sysid.diagnose import DiagnoseConfig
    from sim2real.sysid.diagnose import diagnose as run_diagnosis

    if episodes < 2:
        raise config_lib.ConfigError(f"episodes={episodes}: the loop needs >= 2 (the last one is held out)")
    rolls, what = from_run(run_dir, target, episodes, seed, run_seed, noise, deterministic, until_end=until_end)
    paths = save(rolls, what, os.path.join(out, "recordings"))
    model = env_model_path(env_class(base.env))
    # only effects the training env can express: its physics names them as ``kind:target`` (the
    # targets are names in its own MJCF, which the diagnosis checks), and every parameter of an
    # effect must be one of its physics' (a payload at a fitted distance along the pole, or a
    # backlash's motor-side inertia, which ``dr.from_diagnosis`` would refuse, is not searched)
    env = make(base.env, **dict(base.env_options))
    env_names = from_diagnosis.expressible(env)
    env_targets = sorted({n.split(":", 1)[1] for n in env_names if ":" in n})
    dcfg = config_lib.load(DiagnoseConfig, [f"model={model}", f"recordings=[{','.join(paths[:-1])}]",
                                            f"heldout=[{paths[-1]}]", f"out={os.path.join(out, 'diagnosis')}",
                                            f"progress={str(progress).lower()}"] + list(diagnose_options))
    dcfg = dataclasses.replace(dcfg, targets=tuple(env_targets), expressible=tuple(env_names))
    return paths, what, run_diagnosis(dcfg)


def retrain(run_dir: str, base: TrainConfig, out: str, d: dict, run_seed: int = 0, progress: bool = False,
            warm_start: bool = False, fallback: DRConfig | None = None, warm_std: float = 0.0):
    """Step 3: ``base`` trained on ``out/diagnosis`` (``d``, its ``diagnosis.json``) in ``out/run``;
    returns ``(train's result, the dr it trained on, why the diagnosis was not used or None)``.
    ``warm_start``: from the policy of ``run_dir`` (seed ``run_seed`` for a one-seed ``base``, else
    each seed from its own), restarted at action std ``warm_std`` where that is set
    (``LoopConfig.warm_std``). ``fallback``: the randomisation to train on when the diagnosis is
    ``unusable`` (``LoopConfig.fallback``)."""
    import warnings

    from sim2real.algos import from_diagnosis
    from sim2real.envs import make
    from sim2real.training.driver import train

    env = make(base.env, **dict(base.env_options))
    why = unusable(d)
    dr = dataclasses.replace(base.dr, from_diagnosis=os.path.join(out, "diagnosis"))
    if why and fallback is not None and fallback.params:
        dr = dataclasses.replace(fallback, from_diagnosis="")
        print(f"loop: {why}; training on the fallback box ({', '.join(fallback.params)}) instead")
    elif why:
        warnings.warn(f"loop: {why}; no fallback box given (fallback.params=...), so it trains on it anyway",
                      stacklevel=2)
    cfg = dataclasses.replace(base, name="run", out_dir=out, resume=False, overwrite=False, progress=progress, dr=dr)
    if dr.from_diagnosis:
        need = from_diagnosis.delay_line(dr.from_diagnosis, env, dr.diagnosis_k, dr.diagnosis_box)
        if need > env.config.max_delay:
            print(f"loop: the diagnosed delay's box reaches {need} control steps, beyond env '{base.env}''s "
                  f"delay line of {env.config.max_delay}: trained with env_options.max_delay={need}")
            cfg = dataclasses.replace(cfg, env_options={**dict(base.env_options), "max_delay": need})
    if warm_start:
        cfg = dataclasses.replace(cfg, algo_options={**cfg.algo_options, "warm_start": os.path.abspath(run_dir),
                                                     "warm_start_seed": run_seed if base.num_seeds == 1 else -1,
                                                     **({"warm_std": warm_std} if warm_std else {})})
    return train(cfg), dr, why
