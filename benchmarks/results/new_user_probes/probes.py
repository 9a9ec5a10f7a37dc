"""Models and recordings a new user might bring, none of them from the benchmark's generator:
each probe writes a nominal model, simulates a "true" plant with native MuJoCo (``mj_step``; the
hidden physics set through MuJoCo's own attributes), logs 3 recordings of 8 s at 200 Hz (250 Hz
where the model's step does not divide 5 ms) with position noise, and runs the diagnosis on 2,
holding out the third. Prints one line per probe: truth, answer, values, held-out error, notes
that matter. ``python benchmarks/results/new_user_probes/probes.py [WORK]`` (2-core CPU: ~3 min).
"""
import json
import os
import sys

import mujoco
import numpy as np

ARM = """<mujoco model="probe_arm">
  <compiler angle="degree" autolimits="true"/>
  <option timestep="0.001" integrator="implicitfast"/>
  <default>
    <default class="link"><geom type="capsule" size="0.03" density="800"/></default>
    <joint damping="0.05" armature="0.002"/>
  </default>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" range="-170 170"/>
      <geom class="link" fromto="0 0 0 0.3 0 0"/>
      <body name="lower" pos="0.3 0 0">
        <joint name="elbow" type="hinge" axis="0 1 0" range="-150 150" {truth}/>
        <geom class="link" fromto="0 0 0 0.25 0 0"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <cylinder name="hyd" joint="shoulder" timeconst="0.02" area="0.002" ctrlrange="0 1000"/>
    <motor name="elb" joint="elbow" gear="5" ctrlrange="-1 1" forcerange="-4 4"/>
  </actuator>
</mujoco>"""

TENDON = """<mujoco model="probe_tendon">
  <option timestep="0.002" integrator="RK4"/>
  <worldbody>
    <body name="bar" pos="0 0 0.5">
      <joint name="pivot" type="hinge" axis="0 1 0" {truth}/>
      <geom type="box" size="0.2 0.02 0.02" pos="0.2 0 0" mass="0.4"/>
    </body>
  </worldbody>
  <tendon><fixed name="cable"><joint joint="pivot" coef="0.05"/></fixed></tendon>
  <actuator><motor name="winch" tendon="cable" ctrlrange="-20 20"/></actuator>
</mujoco>"""

GRIPPER = """<mujoco model="gripper">
  <option timestep="0.001" integrator="implicitfast" gravity="0 0 0"/>
  <worldbody>
    <body name="palm">
      <body name="f1" pos="0 0.05 0">
        <joint name="j1" type="slide" axis="0 1 0" range="-0.04 0.04" damping="2"/>
        <geom type="box" size="0.01 0.005 0.03" mass="0.08"/>
      </body>
      <body name="f2" pos="0 -0.05 0">
        <joint name="j2" type="slide" axis="0 -1 0" range="-0.04 0.04" damping="2" {truth}/>
        <geom type="box" size="0.01 0.005 0.03" mass="0.08"/>
      </body>
    </body>
  </worldbody>
  <equality><joint joint1="j2" joint2="j1" polycoef="0 1 0 0 0"/></equality>
  <actuator><motor name="m" joint="j1" ctrlrange="-5 5"/></actuator>
</mujoco>"""

URDF = """<?xml version="1.0"?>
<robot name="pend">
  <link name="base"/>
  <link name="arm">
    <inertial><origin xyz="0 0 -0.25"/><mass value="0.5"/>
      <inertia ixx="0.0105" iyy="0.0105" izz="0.0001" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="pivot" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="1 0 0"/></joint>
</robot>"""

# name: (model text, its suffix, the truth's attribute (or a function of the compiled model), the truth in words,
#        the drive: "multisine" through ctrl, "torque" through qfrc_applied, "swing" released from rest,
#        "spin" launched over the top)
PROBES = {
    "arm_cylinder_motor_friction": (ARM, "xml", 'frictionloss="0.3"', "coulomb_friction@elbow 0.3 N m", "multisine"),
    "tendon_rk4_damping": (TENDON, "xml", 'damping="0.08"', "viscous_damping@pivot 0.08 N m s/rad", "multisine"),
    "gripper_equality_friction": (GRIPPER, "xml", 'frictionloss="0.6"', "coulomb_friction@j2 0.6 N (j1 and j2 tied)",
                                  "steps"),
    "urdf_free_swing_damping": (URDF, "urdf", lambda m: m.dof_damping.__setitem__(0, 0.004),
                                "viscous_damping@pivot 0.004 N m s/rad", "swing"),
    "urdf_qfrc_damping": (URDF, "urdf", lambda m: m.dof_damping.__setitem__(0, 0.004),
                          "viscous_damping@pivot 0.004 N m s/rad", "torque"),
    "urdf_spinning_wrapped": (URDF, "urdf", lambda m: m.dof_damping.__setitem__(0, 0.004),
                              "viscous_damping@pivot 0.004 N m s/rad (angle logged in (-pi, pi])", "spin"),
}


def record(name, model_text, suffix, truth, drive, work):
    nominal = os.path.join(work, f"{name}.{suffix}")
    if suffix == "urdf":
        open(nominal, "w").write(model_text)
        m = mujoco.MjModel.from_xml_path(nominal)
        truth(m)
    else:
        open(nominal, "w").write(model_text.format(truth=""))
        m = mujoco.MjModel.from_xml_string(model_text.format(truth=truth))
    sub = int(round(0.005 / m.opt.timestep))
    period = sub * m.opt.timestep  # the samples' true spacing (5 ms, or 4 ms for a 2 ms step)
    rng = np.random.default_rng(0)
    paths = []
    for r in range(3):
        d = mujoco.MjData(m)
        if drive == "swing":
            d.qpos[0] = 1.0 + 0.3 * r
        if drive == "spin":  # over the top, the angle logged wrapped as an encoder gives it
            d.qvel[0] = 14.0 + r
        freqs, phases = rng.uniform(0.2, 3, (max(m.nu, 1), 5)), rng.uniform(0, 6.28, (max(m.nu, 1), 5))
        levels = rng.uniform(-3, 3, 60)
        cols = [f"qpos:{m.joint(j).name}" for j in range(m.njnt)]
        cols += [f"ctrl:{m.actuator(a).name}" for a in range(m.nu)] + (["qfrc:pivot"] if drive == "torque" else [])
        rows = []
        for k in range(int(8.0 / period)):
            t = k * period
            u = np.sin(2 * np.pi * freqs * t + phases).sum(1) / 2.5
            if drive == "multisine":
                lo, hi = m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1]
                d.ctrl[:] = np.clip(lo + (u + 1) / 2 * (hi - lo), lo, hi) if name.startswith("arm") else u * 8
                if name.startswith("arm"):
                    d.ctrl[1] = np.clip(u[1] * 0.8, -1, 1)
            elif drive == "steps":
                d.ctrl[:] = np.clip(levels[int(t / 0.2) % 60] + 0.8 * np.sin(2 * np.pi * 1.3 * t), -5, 5)
            elif drive == "torque":
                d.qfrc_applied[0] = 0.6 * np.sin(2 * np.pi * 0.5 * t + r) + 0.3 * np.sin(2 * np.pi * 1.7 * t)
            noise = 1e-4 if name.startswith("gripper") else 1e-3
            q = d.qpos + rng.normal(0, noise, m.nq)
            if drive == "spin":
                q = np.arctan2(np.sin(q), np.cos(q))
            rows.append([t + 3.0, *q, *d.ctrl,
                         *([d.qfrc_applied[0]] if drive == "torque" else [])])
            for _ in range(sub):
                mujoco.mj_step(m, d)
        paths.append(os.path.join(work, f"{name}_{r}.csv"))
        np.savetxt(paths[-1], np.array(rows), delimiter=",", header="time," + ",".join(cols), comments="")
    return nominal, paths


def main(work):
    os.makedirs(work, exist_ok=True)
    print("| probe | truth | named | values | held-out NRMSE before -> after | seconds |")
    print("|---|---|---|---|---|---|")
    for name, (text, suffix, truth, words, drive) in PROBES.items():
        nominal, paths = record(name, text, suffix, truth, drive, work)
        diagnose_and_print(name, words, nominal, paths, work)


def diagnose_and_print(name, words, nominal, paths, work, train=2, **options):
    """Diagnose a probe's model on its first ``train`` recordings, the rest held out (none: the
    training recordings' tails; ``options``: other ``DiagnoseConfig`` settings), and print its
    table row (and write its notes beside the diagnosis); an error is printed as the answer."""
    from sim2real.sysid.diagnose import DiagnoseConfig, diagnose

    try:
        d = diagnose(DiagnoseConfig(model=nominal, recordings=tuple(paths[:train]), heldout=tuple(paths[train:]),
                                    out=os.path.join(work, name + "_diagnosis"), overwrite=True, plots=False,
                                    progress=False, **options))
    except Exception as e:  # a probe is a user: what they would see is the finding
        print(f"| {name} | {words} | error: {type(e).__name__}: {str(e)[:300]} | | | |", flush=True)
        return
    named = " + ".join(f"{s['effect']}@{s['target']}" if s["target"] else s["effect"] for s in d["selected"]) or d["answer"]
    if d["answer"] == "inconclusive" and d["selected"]:  # (effects fitted, the answer held back: the notes say why)
        named = f"inconclusive ({named})"
    values = ", ".join(f"{k} {v:.4g}" for s in d["selected"] for k, v in s["params"].items()
                       if not k.endswith(("_vel", "_r")))
    masses = ", ".join(f"{n} {r['nominal']:.4g} -> {r['fitted']:.4g}" for n, r in d["nominal_refit"].items()
                       if n.startswith("mass:"))
    f = d["fit"]
    print(f"| {name} | {words} | {named} | {values}; {masses} | {f['before']:.4g} -> {f['after']:.4g} | "
          f"{d['seconds']} |", flush=True)
    with open(os.path.join(work, name + "_notes.json"), "w") as fh:
        json.dump(d["notes"], fh, indent=1)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes")
