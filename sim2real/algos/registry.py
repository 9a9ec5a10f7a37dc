"""Algorithm names -> builders of ``OuterLoop``s (``algos/base.py`` states the contract)."""
from __future__ import annotations

from sim2real.common import config as config_lib
from sim2real.physics.params import UnknownNameError, unknown_name_message


def _udr(env, cfg):
    from sim2real.algos.udr import UDR, UDRConfig

    opts = config_lib.from_dict(UDRConfig, cfg.algo_options, "algo_options.")
    algo = UDR(env, cfg.ppo, cfg.dr, cfg.num_updates)
    algo.warm_start_from, algo.warm_start_seed, algo.warm_std = opts.warm_start, opts.warm_start_seed, opts.warm_std
    return algo


BUILDERS = {"udr": _udr}
# algo -> the algo_options a resumed run may change (inputs each call brings anew, e.g. SimOpt's
# recordings of the current policy); every other setting is the saved run's (``train.resume_config``)
RESUMABLE_OPTIONS: dict[str, tuple[str, ...]] = {}


def register(name, builder, resumable_options: tuple[str, ...] = ()):
    BUILDERS[name] = builder
    RESUMABLE_OPTIONS[name] = tuple(resumable_options)


def resumable_options(name: str) -> tuple[str, ...]:
    """``algo_options`` keys of algorithm ``name`` that ``resume=true`` may change."""
    _load_all()
    return RESUMABLE_OPTIONS.get(name, ())


def build(name: str, env, cfg):
    """The algorithm ``name`` for ``env`` and training config ``cfg`` (an ``OuterLoop``)."""
    from sim2real.algos.base import OuterLoop

    _load_all()
    if name not in BUILDERS:
        raise UnknownNameError(unknown_name_message("algo", name, sorted(BUILDERS)))
    algo = BUILDERS[name](env, cfg)
    if not isinstance(algo, OuterLoop):
        raise TypeError(f"algo '{name}' built a {type(algo).__name__}, not an OuterLoop (algos/base.py: the "
                        "contract the training driver calls)")
    return algo


def _load_all():
    # every module of this package is imported once: an algorithm in its own module registers
    # itself on import, so adding one is that file (plus its test), not a line here
    import importlib
    import pkgutil

    import sim2real.algos as pkg

    for m in pkgutil.iter_modules(pkg.__path__):
        importlib.import_module(f"{pkg.__name__}.{m.name}")
