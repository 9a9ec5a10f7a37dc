"""Algorithm names -> builders of ``OuterLoop``s (``algos/base.py`` states the contract)."""
from __future__ import annotations

from sim2real import config as config_lib
from sim2real.physics.params import UnknownNameError, unknown_name_message


def _udr(env, cfg):
    from sim2real.algos.udr import UDR

    if cfg.algo_options:
        raise config_lib.ConfigError(f"algo 'udr' takes no algo_options (got {sorted(cfg.algo_options)})")
    return UDR(env, cfg.ppo, cfg.dr, cfg.num_updates)


BUILDERS = {"udr": _udr}


def register(name, builder):
    BUILDERS[name] = builder


def build(name: str, env, cfg):
    """The algorithm ``name`` for ``env`` and training config ``cfg`` (an ``OuterLoop``)."""
    from sim2real.algos.base import OuterLoop

    _load_optional()
    if name not in BUILDERS:
        raise UnknownNameError(unknown_name_message("algo", name, sorted(BUILDERS)))
    algo = BUILDERS[name](env, cfg)
    if not isinstance(algo, OuterLoop):
        raise TypeError(f"algo '{name}' built a {type(algo).__name__}, not an OuterLoop (algos/base.py: the "
                        "contract the training driver calls)")
    return algo


def _load_optional():
    # algorithms in their own modules register themselves on import
    import importlib

    for mod in ("sim2real.algos.lsdr", "sim2real.algos.simopt", "sim2real.algos.es_maml"):
        try:
            importlib.import_module(mod)
        except ModuleNotFoundError as e:
            if e.name != mod:
                raise
