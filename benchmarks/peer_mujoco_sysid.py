"""A peer, side by side: MuJoCo's own ``mujoco.sysid`` fits the same parameters as the diagnosis.

``mujoco.sysid`` fits the parameters it is given; it does not choose which physics is missing.
So it is handed the right set -- the nominal masses and declared damping plus the parameter of the
effect the case really has, in MuJoCo's native terms (``frictionloss``, joint damping or stiffness,
an actuator force limit, a payload body at the true place) -- and fits them on the same
multiple-shooting segments (same starts: measured positions, the same velocity estimates) with its
default optimizer. The diagnosis gets only the nominal model and searches every effect.

Both fitted models are then scored by one evaluator: native MuJoCo (``mj_step``) predictions of
the held-out recording's segments from measured states, at the diagnosis' physics step (NRMSE of
the joint positions over their spread, mean over joints). Times are wall-clock on this machine.

    python benchmarks/peer_mujoco_sysid.py                       # EMPS + 5 independent cases
    python benchmarks/peer_mujoco_sysid.py cases=[040_belt_stage_coulomb_friction@belt]
"""
from __future__ import annotations

import dataclasses
import json
import os
import sys
import time

import mujoco
import numpy as np

from sim2real.common.cli import settings

import sysid_cases

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "peer_mujoco_sysid")
# tuning-half cases whose effect MuJoCo can express natively (one per kind)
DEFAULT_CASES = ("040_belt_stage_coulomb_friction@belt", "082_rc_servo_pendulum_viscous_damping@servo_joint",
                 "024_linear_axis_joint_stiffness@axis", "014_flywheel_actuator_saturation@vservo",
                 "042_intvel_pendulum_mass_offset@bar")


def _segments(trajs, H, n_tiles_max=40):
    """Segment starts per trajectory: consecutive tiles of H samples (like the diagnosis)."""
    out = []
    for r, tr in enumerate(trajs):
        for s in range(0, len(tr) - H - 1, H):
            out.append((r, s))
    if len(out) > n_tiles_max:
        out = [out[i] for i in np.round(np.linspace(0, len(out) - 1, n_tiles_max)).astype(int)]
    return out


def native_nrmse(model: mujoco.MjModel, trajs, segs, H, substeps) -> float:
    """NRMSE of native predictions of ``segs`` (measured start states, recorded commands)."""
    from sim2real.sysid.derivatives import velocity_state

    m = model
    d = mujoco.MjData(m)
    jq = [m.jnt_qposadr[j] for j in range(m.njnt)]
    errs, meas_all = [], []
    for r, s in segs:
        tr = trajs[r]
        mujoco.mj_resetData(m, d)
        d.qpos[jq] = tr.q[s]
        d.qvel[:] = velocity_state(tr.v[s], tr.a[s], m.opt.timestep)
        for k in range(H):
            d.ctrl[:] = tr.ctrl[s + k]
            d.qfrc_applied[:] = tr.qfrc[s + k]
            for _ in range(substeps):
                mujoco.mj_step(m, d)
            errs.append(d.qpos[jq] - tr.q[s + k + 1])
            meas_all.append(tr.q[s + k + 1])
    e, y = np.array(errs), np.array(meas_all)
    ok = np.isfinite(e).all(1)
    return float(np.mean(np.sqrt(np.mean(e[ok] ** 2, 0)) / (y.std(0) + 1e-12)))


def _set_first(obj, attr: str, value: float) -> None:
    """Set the first coefficient of a joint's ``damping`` / ``stiffness`` (MuJoCo 4 keeps 3)."""
    v = np.array(getattr(obj, attr), float).ravel()
    v[0] = value
    setattr(obj, attr, v)


def _with_sensors(spec: mujoco.MjSpec) -> mujoco.MjSpec:
    for j in spec.joints:
        spec.add_sensor(name=f"{j.name}_pos", type=mujoco.mjtSensor.mjSENS_JOINTPOS, objtype=mujoco.mjtObj.mjOBJ_JOINT,
                        objname=j.name)
    return spec


def fit_with_mujoco_sysid(xml: str, effect: tuple, trajs_train, H: int, substeps: int, h: float):
    """Fit nominal masses + declared damping + the true effect's native parameter with mujoco.sysid."""
    from mujoco import sysid

    spec = _with_sensors(mujoco.MjSpec.from_file(xml))
    spec.option.timestep = h
    m0 = spec.compile()
    params = sysid.ParameterDict()
    # masses (inertia scaled with them), as the diagnosis' nominal re-fit
    for b in range(1, m0.nbody):
        mass = float(m0.body_mass[b])
        if mass <= 0:
            continue
        name = mujoco.mj_id2name(m0, mujoco.mjtObj.mjOBJ_BODY, b)
        ipos, iquat, inertia = m0.body_ipos[b].copy(), m0.body_iquat[b].copy(), m0.body_inertia[b].copy()

        def set_mass(sp, p, name=name, mass=mass, ipos=ipos, iquat=iquat, inertia=inertia):
            body = sp.body(name)
            body.explicitinertial = True
            body.mass = float(p.value[0])
            body.ipos, body.iquat = list(ipos), list(iquat)
            body.inertia = list(inertia * float(p.value[0]) / mass)

        params.add(sysid.Parameter(f"mass:{name}", mass, 1e-3 * mass, 100 * mass, modifier=set_mass))
    for j in range(m0.njnt):
        dmp = float(m0.dof_damping[m0.jnt_dofadr[j]])
        jn = mujoco.mj_id2name(m0, mujoco.mjtObj.mjOBJ_JOINT, j)
        if dmp > 0 and effect[0] != "viscous_damping":
            params.add(sysid.Parameter(f"damping:{jn}", dmp, 0.0, 100 * dmp + 1,
                                       modifier=lambda sp, p, jn=jn: _set_first(sp.joint(jn), "damping", float(p.value[0]))))
    kind, target = effect
    if kind == "coulomb_friction":
        params.add(sysid.Parameter(f"frictionloss:{target}", 1e-3, 0.0, 1e3,
                                   modifier=lambda sp, p: setattr(sp.joint(target), "frictionloss", float(p.value[0]))))
    elif kind == "viscous_damping":
        base = float(m0.dof_damping[m0.jnt_dofadr[mujoco.mj_name2id(m0, mujoco.mjtObj.mjOBJ_JOINT, target)]])
        params.add(sysid.Parameter(f"damping:{target}", base + 1e-3, 0.0, 1e3,
                                   modifier=lambda sp, p: _set_first(sp.joint(target), "damping", float(p.value[0]))))
    elif kind == "joint_stiffness":
        params.add(sysid.Parameter(f"stiffness:{target}", 1e-3, 0.0, 1e6,
                                   modifier=lambda sp, p: _set_first(sp.joint(target), "stiffness", float(p.value[0]))))
    elif kind == "actuator_saturation":
        a = mujoco.mj_name2id(m0, mujoco.mjtObj.mjOBJ_ACTUATOR, target)
        top = float(np.max(np.abs(m0.actuator_ctrlrange[a]))) * 10

        def set_limit(sp, p):
            act = sp.actuator(target)
            act.forcelimited = 1
            act.forcerange = [-float(p.value[0]), float(p.value[0])]

        params.add(sysid.Parameter(f"saturation:{target}", top, 1e-3, 1e5, modifier=set_limit))
    elif kind == "mass_offset":
        # a payload body at the link's far end (where the case put it), its mass fitted
        from sim2real.physics.catalog import link_axis

        b = mujoco.mj_name2id(m0, mujoco.mjtObj.mjOBJ_BODY, target)
        anchor, direction, length = link_axis(m0, b)
        pos = anchor + 2 * length * direction
        child = spec.body(target).add_body(name="peer_payload", pos=list(map(float, pos)))
        child.mass, child.inertia, child.explicitinertial = 1e-4, [1e-9] * 3, True
        params.add(sysid.Parameter(f"payload:{target}", 1e-3, 1e-4, 100.0,
                                   modifier=lambda sp, p: setattr(sp.body("peer_payload"), "mass", float(p.value[0]))))
    else:
        raise ValueError(f"{kind}: MuJoCo has no native parameter for it")
    # the data: the same segments, each a measured rollout from its measured state
    model = spec.compile()
    segs = _segments(trajs_train, H)
    names = [f"{mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)}_pos" for j in range(model.njnt)]
    from sim2real.sysid.derivatives import velocity_state

    init, ctrls, sens = [], [], []
    dt = trajs_train[0].dt
    for r, s in segs:
        tr = trajs_train[r]
        t = np.arange(H + 1) * dt
        init.append(sysid.create_initial_state(model, tr.q[s], velocity_state(tr.v[s], tr.a[s], h)))
        u = tr.ctrl[s: s + H + 1]
        ctrls.append(sysid.TimeSeries.from_control_names(t, u, model))
        sens.append(sysid.TimeSeries.from_names(t, tr.q[s: s + H + 1], model, names))
    seqs = sysid.ModelSequences("case", spec, [f"seg{i}" for i in range(len(segs))], init, ctrls, sens)
    residual_fn = sysid.build_residual_fn(models_sequences=[seqs])
    t0 = time.time()
    opt, _ = sysid.optimize(params, residual_fn, optimizer="mujoco", verbose=False)
    seconds = time.time() - t0
    fitted = {k: float(v.value[0]) for k, v in opt.items()}
    return sysid.apply_param_modifiers(opt, spec), fitted, seconds


def run_case(label: str, work: str) -> dict:
    from sim2real.sysid.diagnose import DiagnoseConfig, diagnose
    from sim2real.sysid.recordings import load_all
    from sim2real.sysid.system import System
    from sim2real.sysid.trajectory import from_recording

    if label == "EMPS":
        from sim2real.sysid import emps

        xml, train, held = emps.NOMINAL_XML, [emps.RECORDINGS["estimation"]], [emps.RECORDINGS["validation"]]
        effect, truth = ("coulomb_friction", "axis"), {"frictionloss:axis": emps.REFERENCE["Fc"]}
        folder = os.path.join(work, "EMPS")
    else:
        case = next(c for c in sysid_cases.build_cases() if c.label == label)
        folder = os.path.join(work, label)
        desc = sysid_cases.generate(case, folder)
        xml = os.path.join(folder, "nominal.xml")
        train = [os.path.join(folder, "train_0.csv"), os.path.join(folder, "train_1.csv")]
        held = [os.path.join(folder, "heldout.csv")]
        e, t, _ = case.effects[0]
        effect = (e, t)
        truth = desc["truth_values"]
    t0 = time.time()
    d = diagnose(DiagnoseConfig(model=xml, recordings=tuple(train), heldout=tuple(held),
                                out=os.path.join(folder, "diagnosis_peer"), overwrite=True, plots=False, progress=False))
    ours_seconds = time.time() - t0
    H, substeps, h = d["horizon_samples"], d["substeps"], d["physics_step"]
    m0 = mujoco.MjModel.from_xml_path(xml)
    system = System(xml, dt=h * substeps, substeps=substeps)
    trajs = [from_recording(r, system) for r in load_all(train, m0)]
    held_trajs = [from_recording(r, system) for r in load_all(held, m0)]
    peer_model, peer_fit, peer_seconds = fit_with_mujoco_sysid(xml, effect, trajs, H, substeps, h)
    nominal = mujoco.MjModel.from_xml_path(xml)
    nominal.opt.timestep = h
    segs = _segments(held_trajs, H)
    row = {"case": label, "effect": f"{effect[0]}@{effect[1]}", "truth": truth,
           "ours_named": [f"{s['effect']}@{s['target']}" for s in d["selected"]],
           "ours_params": {k: v for s in d["selected"] for k, v in s["params"].items()},
           "peer_params": peer_fit, "nominal_nrmse": native_nrmse(nominal, held_trajs, segs, H, substeps),
           "peer_nrmse": native_nrmse(peer_model, held_trajs, segs, H, substeps), "ours_seconds": round(ours_seconds, 1),
           "peer_seconds": round(peer_seconds, 1), "horizon_samples": H}
    if d["fitted_mjcf"]:
        ours = mujoco.MjModel.from_xml_path(os.path.join(folder, "diagnosis_peer", "fitted.xml"))
        ours.opt.timestep = h
        row["ours_nrmse"] = native_nrmse(ours, held_trajs, segs, H, substeps)
    return row


@dataclasses.dataclass
class Settings:
    """cases: case labels (``[a,b]``); work: where generated cases are kept; out: results folder."""
    cases: tuple[str, ...] = ("EMPS", *DEFAULT_CASES)
    work: str = os.path.join("runs", "sysid_cases")
    out: str = OUT


def main(args: Settings):
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for label in args.cases:
        row = run_case(label, args.work)
        rows.append(row)
        print(json.dumps(row), flush=True)
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump(rows, f, indent=1)
    lines = ["| case | effect | truth | sim2real (searched every effect) | mujoco.sysid (given the right parameter) | "
             "held-out NRMSE nominal / sim2real / mujoco.sysid | seconds sim2real / mujoco.sysid |", "|---" * 7 + "|"]
    for r in rows:
        ours = ", ".join(f"{k}={v:.4g}" for k, v in r["ours_params"].items()) or "none named"
        peer = ", ".join(f"{k}={v:.4g}" for k, v in r["peer_params"].items() if not k.startswith(("mass:", "damping:"))
                         or r["effect"].startswith("viscous"))
        truth = ", ".join(f"{v:.4g}" for t in r["truth"].values() for v in (t.values() if isinstance(t, dict) else [t]))
        lines.append(f"| {r['case']} | {r['effect']} | {truth} | {ours} | {peer} | {r['nominal_nrmse']:.4f} / "
                     f"{r.get('ours_nrmse', float('nan')):.4f} / {r['peer_nrmse']:.4f} | {r['ours_seconds']} / {r['peer_seconds']} |")
    with open(os.path.join(args.out, "table.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main(settings(Settings, sys.argv[1:])))
