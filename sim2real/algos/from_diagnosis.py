"""A diagnosis as a training distribution: the fitted physics, and a box of +-k std around it.

``dr.from_diagnosis=runs/diag`` (a diagnosis folder or its ``diagnosis.json``) turns what
``scripts/diagnose.py`` found on the env's own model into the env's physics: every re-fitted
nominal parameter and every parameter of the selected effects (the effect switched on) is set to
its fitted value, and where the fit gave a standard deviation it is randomised over
``value +- dr.diagnosis_k * std`` (clipped to the physical bounds). With ``dr.diagnosis_box=span``
the box also reaches back to the env's own value of the parameter (a friction from 0, a mass
from the model's): the fit's std says how well the recordings pin the value down, not how far
the plant may be from the fitted model, and a box spanning the model the policy was trained on
and the one found hedges between the two (and keeps the easier physics a policy learns first
in the box; the closed-loop benchmark's cart-pole, README). ``dr.diagnosis_box=centred`` goes as
far past the fitted value as back to the env's own (``box``). The diagnosis' names are the
env's (both come from ``physics/catalog.py``) with three translations: the delay is in recording
samples there and in control steps here, a joint's declared damping is the env's
``joint_damping`` where that parameter drives exactly that joint, and a lag shared by every
actuator (``motor_lag_all``) is each actuator's ``motor_lag``. A re-fitted mass the diagnosis
itself reports as standing in for missing physics (more than ``FAR_MASS`` times off the model's:
``diagnose.far_masses``) is not trained on: the env keeps its own, with a warning. What the user's
``dr`` already names wins. ``train`` resolves this once, before the run folder is written, so ``config.yaml``
holds the resulting box and fixed values (and a resume reads them, not the diagnosis).
"""
from __future__ import annotations

import dataclasses
import json
import math
import os
import typing
import warnings

import mujoco
import numpy as np

from sim2real.algos.base import DiagnosisBox, DRConfig
from sim2real.common.config import ConfigError
from sim2real.envs.base import Env
from sim2real.physics import catalog
from sim2real.physics.kinds.lag import SHARED as SHARED_LAG
from sim2real.sysid.select import FAR_MASS, is_far_mass

# fitted alongside an effect but with no counterpart in the envs' physics (a payload's distance
# along the link, the motor inertia crossing a backlash): an error when a selected effect has them
_HELPERS = ("payload_r", "payload_x", "payload_y", "payload_z", "backlash_inertia")


def load(path: str) -> dict:
    """The ``diagnosis.json`` of a diagnosis folder (or the file itself)."""
    f = os.path.join(path, "diagnosis.json") if os.path.isdir(path) else path
    if not os.path.exists(f):
        raise ConfigError(f"dr.from_diagnosis={path}: no diagnosis.json there (run scripts/diagnose.py first)")
    try:
        with open(f) as fh:
            d = json.load(fh)
    except json.JSONDecodeError as e:
        raise ConfigError(f"dr.from_diagnosis: {f} is not valid JSON ({e})") from None
    for key in ("model", "fitted_params", "selected", "nominal_refit", "sample_period"):
        if key not in d:
            raise ConfigError(f"dr.from_diagnosis: {f} has no '{key}' (not a diagnosis.json of this version)")
    d["_path"] = f
    return d


def check_same_model(d: dict, env: Env) -> None:
    """The diagnosed model must be the env's: the same joints (names and types) and actuators."""
    try:
        m = mujoco.MjModel.from_xml_path(d["model"])
    except Exception as e:
        raise ConfigError(f"dr.from_diagnosis: the diagnosed model '{d['model']}' cannot be loaded ({e})") from None
    em = env.mj_model
    J, A = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_ACTUATOR
    mine = (catalog.names(em, J), list(em.jnt_type), catalog.names(em, A))
    theirs = (catalog.names(m, J), list(m.jnt_type), catalog.names(m, A))
    if mine != theirs:
        raise ConfigError(f"dr.from_diagnosis: the diagnosed model '{d['model']}' is not env '{env.name}''s "
                          f"(joints {theirs[0]}, actuators {theirs[2]}; the env has joints {mine[0]}, "
                          f"actuators {mine[2]}); diagnose the env's own MJCF")


def env_values(d: dict, env: Env) -> dict[str, tuple[float, float]]:
    """``{env parameter: (fitted value, std)}`` (std NaN where the fit gave none)."""
    check_same_model(d, env)
    std = {n: r.get("std") for n, r in d["nominal_refit"].items()}
    for s in d["selected"]:
        std.update(s.get("std", {}))
    selected_names = {n for s in d["selected"] for n in list(s.get("params", {})) + list(s.get("std", {}))}
    em = env.mj_model
    damping_dofs = list(env.joint_damping_dofs(em))
    out, missing, shared = {}, [], None
    for name, value in d["fitted_params"].items():
        sd = std.get(name)
        sd = float("nan") if sd is None else float(sd)
        kind, _, target = name.partition(":")
        if kind in _HELPERS:
            if name in selected_names:
                missing.append(name)
            continue
        if name == SHARED_LAG:  # (below, once every actuator's own lag is known)
            shared = (float(value), sd)
            continue
        r = d["nominal_refit"].get(name)
        if kind == "mass" and r and is_far_mass(float(r["nominal"]), float(r["fitted"])):
            # the hopper's first loop: a policy that fell at once gave masses 13-18x the model's
            warnings.warn(f"dr.from_diagnosis: {name} was re-fitted {value:.4g}, more than {FAR_MASS:g}x off the "
                          f"model's {_default_in_diagnosis(d, name):.4g} (the diagnosis' own note: it stands in "
                          f"for missing physics); env '{env.name}' keeps its own", stacklevel=2)
            continue
        if name == "action_delay":
            value, sd = value * _steps_per_sample(d, env), sd * _steps_per_sample(d, env)
        elif kind == "damping":
            j = mujoco.mj_name2id(em, mujoco.mjtObj.mjOBJ_JOINT, target)
            if j >= 0 and damping_dofs == [int(em.jnt_dofadr[j])]:
                name = "joint_damping"
            elif f"viscous:{target}" in env.spec:
                # a re-fitted damping on a joint the env randomises only through its viscous effect
                # (added to the declared damping): the fit's excess over the nominal; the env
                # cannot take damping away, so a lower fit holds the nominal, with a warning
                name, value = f"viscous:{target}", value - _default_in_diagnosis(d, name)
                if value < 0:
                    warnings.warn(f"dr.from_diagnosis: {kind}:{target} was fitted {-value:.3g} below the "
                                  f"model's nominal; env '{env.name}' can only add damping there, so it "
                                  f"keeps the nominal", stacklevel=2)
                    value = 0.0
        if name not in env.spec:
            if not math.isclose(value, _default_in_diagnosis(d, name), rel_tol=1e-9, abs_tol=1e-12):
                missing.append(name)
            continue
        out[name] = (float(value), sd)
    if shared is not None and shared[0] > 0:  # one lag on every actuator: each one's own, where it has none
        for an in catalog.names(em, mujoco.mjtObj.mjOBJ_ACTUATOR):
            if not out.get(f"motor_lag:{an}", (0.0,))[0] > 0:
                out[f"motor_lag:{an}"] = shared
    if missing:
        raise ConfigError(f"dr.from_diagnosis={d['_path']}: fitted parameter(s) {', '.join(missing)} have no "
                          f"counterpart in env '{env.name}''s physics (its parameters: {', '.join(env.spec.names)})")
    return out


def expressible(env: Env) -> list[str]:
    """The diagnosis' parameter names this env can take (``DiagnoseConfig.expressible``): its
    physics' own, and ``motor_lag_all`` where every actuator has a ``motor_lag`` (``env_values``
    gives it to each)."""
    names = list(env.spec.names)
    acts = catalog.names(env.mj_model, mujoco.mjtObj.mjOBJ_ACTUATOR)
    if len(acts) > 1 and all(f"motor_lag:{an}" in names for an in acts):
        names.append(SHARED_LAG)
    return names


def delay_line(path: str, env: Env, k: float, kind: str = "std") -> int:
    """Control steps of delay line that a diagnosis' box needs: the top of its fitted
    ``action_delay``'s box (``box``; ``ceil(delay + k std)`` for ``std`` and ``span``, ``ceil(delay)``
    without a std, ``ceil(2 delay)`` or more for ``centred``) in the env's steps; 0 without a
    delay. ``scripts/loop.py`` raises ``env_options.max_delay`` to it, since a delay beyond the
    env's line is refused (the line's length is not in the observation, so a warm-started policy
    runs unchanged on a longer one)."""
    d = load(path)
    value = d["fitted_params"].get("action_delay")
    if value is None:
        return 0
    sd = next((s["std"]["action_delay"] for s in d["selected"] if s.get("std", {}).get("action_delay") is not None),
              None)
    top = box(float(value), float(sd) if sd is not None else float("nan"), 0.0, k, kind)[1]
    return int(math.ceil(top * _steps_per_sample(d, env) - 1e-9))


def _steps_per_sample(d: dict, env: Env) -> float:
    """The delay is in samples of the recordings in a diagnosis, in control steps in an env."""
    return float(d["sample_period"]) / env.dt


def _default_in_diagnosis(d: dict, name: str) -> float:
    r = d["nominal_refit"].get(name)
    return float(r["nominal"]) if r else 0.0


BOXES = typing.get_args(DiagnosisBox)


def box(value: float, sd: float, default: float, k: float, kind: str) -> tuple[float, float]:
    """The training range of one fitted parameter (before clipping to its bounds), in its units.

    ``std``: ``value +- k sd``. ``span``: that, stretched back to the env's own ``default``.
    ``centred``: ``value +- max(k sd, |value - default|)``: the distance the fit moved from the
    model is taken as the scale of the model's error, and the fit as the best guess in the middle
    of it: a tight fit of a 40 ms lag trains on 0-80 ms, where ``span`` stops at the fit and puts
    a plant just past it at the box's edge. A NaN ``sd`` counts as 0."""
    k_sd = k * sd if np.isfinite(sd) else 0.0
    if kind == "centred":
        half = max(k_sd, abs(value - default))
        return value - half, value + half
    lo, hi = value - k_sd, value + k_sd
    if kind == "span":
        lo, hi = min(lo, default), max(hi, default)
    return lo, hi


def resolve(dr: DRConfig, env: Env) -> DRConfig:
    """``dr`` with the diagnosis' physics added (unchanged when ``dr.from_diagnosis`` is empty)."""
    if not dr.from_diagnosis:
        return dr
    if not dr.diagnosis_k > 0:
        raise ConfigError(f"dr.diagnosis_k={dr.diagnosis_k}: must be > 0 (the box is value +- k std)")
    if dr.diagnosis_box not in BOXES:
        raise ConfigError(f"dr.diagnosis_box={dr.diagnosis_box!r}: must be 'std' (value +- k std), 'span' "
                          "(that box reaching back to the env's own value) or 'centred' (and as far past the value)")
    d = load(dr.from_diagnosis)
    params, low, high = list(dr.params), list(dr.low), list(dr.high)
    fixed = dict(dr.fixed)
    for name, (value, sd) in env_values(d, env).items():
        if name in params or name in fixed:  # the user's own setting wins
            continue
        p = env.spec[name]
        if not p.low <= value <= p.high:
            hint = " (raise env_options.max_delay; scripts/loop.py does)" if name == "action_delay" else ""
            raise ConfigError(f"dr.from_diagnosis: fitted {name} = {value:g} {p.unit} is outside the env's bounds "
                              f"[{p.low:g}, {p.high:g}]{hint}")
        lo, hi = box(value, sd, float(p.default), dr.diagnosis_k, dr.diagnosis_box)
        lo, hi = max(p.low, lo), min(p.high, hi)
        if hi - lo > 1e-6 * max(abs(value), 1e-6):  # (no std and ``std``: lo == hi)
            params.append(name)
            low.append(float(lo))
            high.append(float(hi))
        else:  # no spread known (or none at all; ``span``: the env's own value): the fitted value
            fixed[name] = float(value)
    return dataclasses.replace(dr, params=tuple(params), low=tuple(low), high=tuple(high), fixed=fixed)
