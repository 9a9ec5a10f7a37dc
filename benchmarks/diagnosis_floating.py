"""The diagnosis on ball and free joints: a conical swing on a ball-jointed shoulder and a
free-floating base carrying a 2-link arm, each effect hidden alone at two sizes, and
parameter-only cases (the truth's masses off, nothing missing).

    python benchmarks/diagnosis_floating.py                 # every case, one at a time
    python benchmarks/diagnosis_floating.py only=space_arm
    python benchmarks/diagnosis_floating.py list=tuning jobs=8 out=/tmp/ft   # the tuning list

``list=check`` (seeds 8000-8029) is the list the README reports; ``list=tuning`` (seeds
9000-9029) is drawn the same way from other seeds, and is the one changes made for these
systems are tuned on (``results/diagnosis_floating/README.md``).

The truth is native MuJoCo (``mj_step``), its effects written here, not through
``sim2real.physics``: MuJoCo's ``frictionloss`` and ``damping`` (on the ball joint's three dofs
alike), a delay line on the logged commands at the physics rate, a ``general`` actuator with
``filterexact`` dynamics for a lag, ``forcerange`` for a force limit, a point-mass body at a
link's tip for a payload. The truth steps at a quarter of the model's timestep; logs at 100 or
200 Hz, 8 s, random torque steps, position noise 1e-4 or 1e-3 (quaternion components alike), a
measured ``qvel`` (noise 1e-2) in half the cases, three recordings (two fitted, one held out).

Nothing of the diagnosis was tuned on these cases (``results/diagnosis_floating/README.md`` says
how often the list was looked at). Scoring as ``diagnosis_independent.py``: a single effect is
named when exactly it is selected; a parameter-only case when none is; a named effect's main
parameter within 25% of the truth. Writes ``<out>/cases.csv`` and ``<out>/summary.md``.
"""
from __future__ import annotations

import csv
import dataclasses
import os
import sys
import time
import traceback

import mujoco
import numpy as np

from sim2real.common.cli import settings
from sim2real.envs.parallel import cpu_cores

from diagnosis_independent import _key, _param_errors, named_keys  # one scorer for both benchmarks

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "diagnosis_floating")

# ``{ROOT}``: the base's joint; ``{SH}``, ``{EL}``, ``{EL2}``: extra attributes of the shoulder /
# elbow joints; ``{PAYLOAD}``: a body at the last link's tip; ``{ACT}``: the actuators
_BALL_ARM = """<mujoco model="ball_arm">
  <option timestep="{ts}" gravity="0 0 -9.81"/>
  <default><geom contype="0" conaffinity="0"/></default>
  <worldbody>
    <body name="base" pos="0 0 1">
      <joint name="shoulder" type="ball"{SH}/>
      <geom type="sphere" size="0.05" mass="{m_base}"/>
      <body name="link">
        <joint name="elbow" type="hinge" axis="0 1 0" damping="0.02"{EL}/>
        <geom type="capsule" fromto="0 0 0 0.3 0 -0.1" size="0.02" mass="{m_link}"/>{PAYLOAD}
      </body>
    </body>
  </worldbody>
  <actuator>{ACT}</actuator>
</mujoco>"""

_SPACE_ARM = """<mujoco model="space_arm">
  <option timestep="{ts}" gravity="0 0 0"/>
  <default><geom contype="0" conaffinity="0"/></default>
  <worldbody>
    <body name="base" pos="0 0 0">
      <freejoint name="root"/>
      <geom type="box" size="0.1 0.08 0.06" mass="{m_base}"/>
      <body name="upper" pos="0.1 0 0">
        <joint name="shoulder" type="hinge" axis="0 0 1" damping="0.01"{SH}/>
        <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.02" mass="{m_upper}"/>
        <body name="lower" pos="0.25 0 0">
          <joint name="elbow" type="hinge" axis="0 0 1" damping="0.01"{EL}/>
          <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.015" mass="{m_lower}"/>{PAYLOAD}
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>{ACT}</actuator>
</mujoco>"""

SYSTEMS = {
    "ball_arm": dict(xml=_BALL_ARM, masses={"m_base": 0.6, "m_link": 0.3}, tip=(0.3, 0, -0.1), payload_of=0.3,
                     acts=[("m", "elbow")], amp=0.5),
    "space_arm": dict(xml=_SPACE_ARM, masses={"m_base": 2.0, "m_upper": 0.3, "m_lower": 0.2}, tip=(0.2, 0, 0),
                      payload_of=0.2, acts=[("m1", "shoulder"), ("m2", "elbow")], amp=0.3),
}

# effect -> (target, two sizes); sizes in SI units (N m, N m s/rad, s, fraction of the command's
# largest force for a limit, fraction of the link's mass for a payload)
EFFECTS = {
    "ball_arm": [("coulomb_friction", "shoulder", (0.01, 0.03)), ("viscous_damping", "shoulder", (0.01, 0.03)),
                 ("coulomb_friction", "elbow", (0.03, 0.08)), ("action_delay", "", (0.008, 0.017)),
                 ("motor_lag", "m", (0.02, 0.045)), ("actuator_saturation", "m", (0.6, 0.35)),
                 ("mass_offset", "link", (0.3, 0.6))],
    "space_arm": [("coulomb_friction", "shoulder", (0.01, 0.03)), ("coulomb_friction", "elbow", (0.01, 0.03)),
                  ("action_delay", "", (0.008, 0.017)), ("motor_lag", "m1", (0.02, 0.045)),
                  ("actuator_saturation", "m2", (0.6, 0.35)), ("mass_offset", "lower", (0.3, 0.6))],
}
FIRST_SEED = {"check": 8000, "tuning": 9000}


@dataclasses.dataclass(frozen=True)
class Case:
    seed: int
    system: str
    effect: str          # "none": parameter-only
    target: str
    size: float
    rate: float          # Hz
    timestep: float      # the model's (s)
    noise: float         # position noise (rad, m, quaternion components)
    qvel: bool

    @property
    def label(self) -> str:
        what = "none" if self.effect == "none" else (self.effect if not self.target else f"{self.effect}@{self.target}")
        return f"{self.seed}_{self.system}_{what}"


def cases(which: str = "check") -> list[Case]:
    if which not in FIRST_SEED:
        raise ValueError(f"list={which!r}: not one of {sorted(FIRST_SEED)}")
    first = FIRST_SEED[which]
    out = []
    for system, effects in EFFECTS.items():
        for effect, target, sizes in effects:
            out += [(system, effect, target, s) for s in sizes]
        out += [(system, "none", "", 0.8), (system, "none", "", 1.25)]
    res = []
    for k, (system, effect, target, size) in enumerate(out):
        rng = np.random.default_rng(first + k)
        res.append(Case(first + k, system, effect, target, float(size), float(rng.choice([100.0, 200.0])),
                        float(rng.choice([0.001, 0.002])), float(rng.choice([1e-4, 1e-3])), bool(rng.uniform() < 0.5)))
    return res


def _mjcf(case: Case, truth: bool) -> str:
    s = SYSTEMS[case.system]
    masses = dict(s["masses"])
    if truth and case.effect == "none":   # parameter-only: the first link's mass off (x0.8, x1.25)
        first = [k for k in masses if k != "m_base"][0]
        masses[first] *= case.size
    sh = el = payload = ""
    if truth and case.effect == "coulomb_friction":
        attr = f' frictionloss="{case.size:.9g}"'
        sh, el = (attr, "") if case.target == "shoulder" else ("", attr)
    if truth and case.effect == "viscous_damping":
        sh = f' damping="{case.size:.9g}"'
    if truth and case.effect == "mass_offset":
        payload = (f'\n        <body name="payload" pos="{" ".join(map(str, s["tip"]))}"><inertial pos="0 0 0" '
                   f'mass="{case.size * s["payload_of"]:.9g}" diaginertia="1e-6 1e-6 1e-6"/></body>')
    acts = []
    for name, joint in s["acts"]:
        extra = ""
        if truth and case.effect == "actuator_saturation" and name == case.target:
            lim = case.size * s["amp"]
            extra = f' forcelimited="true" forcerange="{-lim:.9g} {lim:.9g}"'
        if truth and case.effect == "motor_lag" and name == case.target:
            acts.append(f'<general name="{name}" joint="{joint}" ctrlrange="-1 1" dyntype="filterexact" '
                        f'dynprm="{case.size:.9g}" gainprm="1"{extra}/>')
        else:
            acts.append(f'<motor name="{name}" joint="{joint}" ctrlrange="-1 1"{extra}/>')
    return s["xml"].format(ts=case.timestep, SH=sh, EL=el, PAYLOAD=payload, ACT="".join(acts), **masses)


def _columns(m: mujoco.MjModel) -> tuple[list[str], list[str]]:
    from sim2real.sysid.trajectory import ModelColumns

    mc = ModelColumns(m, "truth")
    return mc.qpos_names, mc.dof_names


def record(case: Case, truth: mujoco.MjModel, run: int, seconds: float = 8.0) -> tuple[list[str], np.ndarray]:
    """One recording ``(header, rows)``: the truth stepped at a quarter of the model's step."""
    rng = np.random.default_rng((case.seed, run))
    s = SYSTEMS[case.system]
    truth.opt.timestep = case.timestep / 4
    d = mujoco.MjData(truth)
    if case.system == "ball_arm":   # a conical swing: tilted, spinning about the vertical
        tilt = rng.uniform(0.1, 0.3)
        d.qpos[:4] = [np.cos(tilt), np.sin(tilt), 0.0, 0.0]
        d.qvel[:3] = [0.0, 0.0, rng.uniform(1.5, 2.5)]
    else:   # drifting and tumbling slowly
        d.qvel[:6] = rng.uniform(-0.2, 0.2, 6)
    dt = 1.0 / case.rate
    T = int(seconds * case.rate)
    nu = truth.nu
    u = np.zeros((T, nu))
    for k in range(T):
        u[k] = u[k - 1] if k and k % max(1, int(0.3 * case.rate)) else rng.uniform(-1, 1, nu) * s["amp"]
    delay = case.size if case.effect == "action_delay" else 0.0
    n = int(round(dt / truth.opt.timestep))
    if truth.na:   # a lag at rest under the first command
        d.act[:] = u[0][[a for a in range(nu) if truth.actuator_actadr[a] >= 0]]
    qn, vn = _columns(truth)
    rows = []
    for k in range(T):
        q = d.qpos + case.noise * rng.standard_normal(truth.nq)
        row = [2.0 + k * dt, *q]
        if case.qvel:
            row += list(d.qvel + 1e-2 * rng.standard_normal(truth.nv))
        rows.append(row + list(u[k]))
        for j in range(n):   # the delay line: the command logged at time t - delay acts now
            t = k * dt + j * truth.opt.timestep - delay
            d.ctrl[:] = u[max(int(np.floor(t / dt + 1e-9)), 0)] if t >= 0 else u[0]
            mujoco.mj_step(truth, d)
    header = ["time"] + [f"qpos:{c}" for c in qn] + ([f"qvel:{c}" for c in vn] if case.qvel else []) + \
        [f"ctrl:{a}" for a, _ in s["acts"]]
    return header, np.array(rows)


def generate(case: Case, folder: str) -> list[str]:
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "nominal.xml"), "w") as f:
        f.write(_mjcf(case, truth=False))
    truth = mujoco.MjModel.from_xml_string(_mjcf(case, truth=True))
    paths = []
    for run in range(3):
        header, rows = record(case, truth, run)
        if not np.all(np.isfinite(rows)):
            raise RuntimeError(f"{case.label}: the truth diverged")
        paths.append(os.path.join(folder, f"run{run}.csv"))
        np.savetxt(paths[-1], rows, delimiter=",", comments="", header=",".join(header), fmt="%.9g")
    return paths


def _truth_param(case: Case) -> tuple[str, float] | None:
    s = SYSTEMS[case.system]
    return {"coulomb_friction": (f"coulomb:{case.target}", case.size), "viscous_damping": (f"viscous:{case.target}", case.size),
            "action_delay": ("action_delay_seconds", case.size), "motor_lag": (f"motor_lag:{case.target}", case.size),
            "actuator_saturation": (f"saturation:{case.target}", case.size * s["amp"]),
            "mass_offset": (f"payload:{case.target}", case.size * s["payload_of"])}.get(case.effect)


def run_case(case: Case, work: str) -> dict:
    from sim2real.sysid.diagnose import DiagnoseConfig, diagnose

    folder = os.path.join(work, case.label)
    row = {"case": case.label, **dataclasses.asdict(case)}
    t0 = time.time()
    try:
        paths = generate(case, folder)
        d = diagnose(DiagnoseConfig(model=os.path.join(folder, "nominal.xml"), recordings=tuple(paths[:2]),
                                    heldout=(paths[2],), out=os.path.join(folder, "diagnosis"), overwrite=True,
                                    plots=False, progress=False))
    except Exception as e:  # noqa: BLE001  (a crash is a wrong answer, reported as such)
        row.update(named="error", correct=False, error=f"{type(e).__name__}: {e}"[:300],
                   seconds=round(time.time() - t0, 1), traceback=traceback.format_exc()[-600:])
        return row
    named = named_keys(d)
    want = [] if case.effect == "none" else [_key(case.effect, case.target)]
    tp = _truth_param(case)
    errs = _param_errors({"truth_values": {want[0]: dict([tp])}}, d) if tp and want else {}
    err = errs.get(want[0], "") if want else ""
    row.update(named=" + ".join(named) or "none", correct=sorted(named) == sorted(want), param_error=err,
               heldout_before=d["fit"]["before"], heldout_after=d["fit"]["after"],
               never_worse=d["fit"]["after"] <= d["fit"]["before"] * (1 + 1e-9), seconds=round(time.time() - t0, 1))
    return row


def summarise(rows: list[dict], jobs: int = 1) -> str:
    def pct(a, b):
        return f"{a}/{b} ({100 * a / b:.0f}%)" if b else "0/0"

    single = [r for r in rows if r["effect"] != "none"]
    none = [r for r in rows if r["effect"] == "none"]
    errs = [r["param_error"] for r in single if r.get("param_error") not in ("", None)]
    L = ["## Ball and free joints (`benchmarks/diagnosis_floating.py`)", "",
         f"- single effects named (exactly, nothing else): **{pct(sum(bool(r['correct']) for r in single), len(single))}**",
         f"- parameter-only cases with an effect named: **{sum(r['named'] != 'none' for r in none)}/{len(none)}**",
         f"- held-out error never worse than the nominal model's: {pct(sum(r.get('never_worse') is True for r in rows), len(rows))}",
         f"- named effects' parameters within 25% of the truth: {pct(sum(e <= 0.25 for e in errs), len(errs))}",
         f"- seconds per case ({cpu_cores()} CPU cores, {jobs} case(s) at a time, the case's generation included): median "
         f"{np.median([r['seconds'] for r in rows]):.1f}, max {max(r['seconds'] for r in rows):.1f}",
         f"- errors (crashes): {sum(r['named'] == 'error' for r in rows)}", "",
         "| case | rate (Hz) | step (ms) | noise | qvel | named | correct | parameter error | held-out before -> after | s |",
         "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        pe = f"{r['param_error']:.3f}" if r.get("param_error") not in ("", None) else ""
        hb = f"{r['heldout_before']:.4g} -> {r['heldout_after']:.4g}" if "heldout_before" in r else r.get("error", "")
        L.append(f"| {r['case']} | {r['rate']:g} | {r['timestep'] * 1e3:g} | {r['noise']:g} | {r['qvel']} | {r['named']} | "
                 f"{'yes' if r['correct'] else 'no'} | {pe} | {hb} | {r['seconds']} |")
    return "\n".join(L) + "\n"


@dataclasses.dataclass
class Settings:
    """list: ``check`` or ``tuning``; only: run the cases whose label contains this; out: results
    folder; work: case folders; jobs: cases at a time (processes)."""
    list: str = "check"
    only: str = ""
    out: str = OUT
    work: str = "/tmp/diagnosis_floating"
    jobs: int = 1


def main(args: Settings) -> list[dict]:
    todo = [c for c in cases(args.list) if args.only in c.label]
    if args.list != "check" and os.path.abspath(args.out) == os.path.abspath(OUT):
        raise ValueError(f"list={args.list}: give out= (the results folder holds the check list's)")
    rows = []

    def show(c, r):
        rows.append(r)
        print(f"-- {c.label:48s} named {r['named']:40s} {r['seconds']:6.1f}s {'ok' if r['correct'] else 'MISS'}", flush=True)

    if args.jobs > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(args.jobs) as ex:
            for c, f in [(c, ex.submit(run_case, c, args.work)) for c in todo]:
                show(c, f.result())
    else:
        for c in todo:
            show(c, run_case(c, args.work))
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "cases.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=sorted({k for r in rows for k in r}))
        w.writeheader()
        w.writerows(rows)
    text = summarise(rows, args.jobs)
    with open(os.path.join(args.out, "summary.md"), "w") as f:
        f.write(text)
    print(text)
    return rows


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
