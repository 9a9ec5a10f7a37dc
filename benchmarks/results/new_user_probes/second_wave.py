"""A second wave of models a new user might bring (``probes.py`` has the first): MuJoCo features
the first wave and the benchmark's generator leave out. Each probe writes a nominal model,
simulates a "true" plant with native MuJoCo (``mj_step``), the hidden physics set through
MuJoCo's own attributes or written here (a delay line on the command, an offset on the logged
angle), logs 3 recordings of 8 s with position noise 1e-3, and runs the diagnosis on 2, holding
out the third. Prints one line per probe like ``probes.py``.
``PYTHONPATH=. python benchmarks/results/new_user_probes/second_wave.py [WORK] [PROBE ...]``.
"""
import os
import sys

import mujoco
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from probes import diagnose_and_print  # noqa: E402  (the same table as the first wave's)

FLYWHEEL = """<mujoco model="flywheel">
  <option timestep="0.001"/>
  <worldbody>
    <body name="wheel">
      <joint name="spin" type="hinge" axis="0 0 1" damping="0.002" {truth}/>
      <geom type="cylinder" size="0.1 0.02" mass="1.0"/>
    </body>
  </worldbody>
  <actuator><intvelocity name="servo" joint="spin" kp="1" kv="0.05" actrange="-1000 1000" ctrlrange="-10 10"/></actuator>
</mujoco>"""

# a vertical 2-link arm on filtered PD servos written as `general` actuators (dyntype filterexact,
# affine bias), masses from geoms; the truth adds a point mass at the lower link's tip
SERVO_ARM = """<mujoco model="servo_arm">
  <option timestep="0.002" integrator="implicit"/>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" axis="0 1 0" damping="0.1"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.025" mass="0.6"/>
      <body name="lower" pos="0 0 -0.3">
        <joint name="elbow" axis="0 1 0" damping="0.05"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.25" size="0.02" mass="0.3"/>
        {truth}
      </body>
    </body>
  </worldbody>
  <actuator>
    <general name="s1" joint="shoulder" dyntype="filterexact" dynprm="0.03" gainprm="40" biastype="affine"
             biasprm="0 -40 -2" ctrlrange="-1.5 1.5"/>
    <general name="s2" joint="elbow" dyntype="filterexact" dynprm="0.03" gainprm="15" biastype="affine"
             biasprm="0 -15 -0.6" ctrlrange="-1.5 1.5"/>
  </actuator>
</mujoco>"""

AXIS = """<mujoco model="axis">
  <option timestep="0.001"/>
  <worldbody>
    <body name="carriage">
      <joint name="x" type="slide" axis="1 0 0" damping="5" range="-0.5 0.5"/>
      <geom type="box" size="0.05 0.05 0.02" mass="2"/>
    </body>
  </worldbody>
  <actuator><position name="p" joint="x" kp="400" kv="30" ctrlrange="-0.3 0.3"/></actuator>
</mujoco>"""

BALL = """<mujoco model="spherical">
  <option timestep="0.001"/>
  <worldbody>
    <body name="bob" pos="0 0 1">
      <joint name="ball" type="ball" {truth}/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.02" mass="0.3"/>
      <geom type="sphere" pos="0 0 -0.4" size="0.04" mass="0.5"/>
    </body>
  </worldbody>
</mujoco>"""

PENDULUM = """<mujoco model="pendulum">
  <option timestep="0.001"/>
  <worldbody>
    <body name="rod" pos="0 0 1">
      <joint name="hinge" axis="0 1 0" damping="0.01" {truth}/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/>
    </body>
  </worldbody>
  <actuator><motor name="m" joint="hinge" ctrlrange="-2 2"/></actuator>
</mujoco>"""

# bodies compensated for gravity (`gravcomp`, as menagerie's arms write it), motors
GRAVCOMP = """<mujoco model="gravcomp_arm">
  <option timestep="0.001" integrator="implicitfast"/>
  <worldbody>
    <body name="l1" pos="0 0 0.5" gravcomp="1">
      <joint name="j1" axis="0 1 0" {truth}/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      <body name="l2" pos="0.3 0 0" gravcomp="1">
        <joint name="j2" axis="0 1 0" damping="0.02"/>
        <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.025" mass="0.5"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor name="a1" joint="j1" ctrlrange="-2 2"/><motor name="a2" joint="j2" ctrlrange="-1 1"/></actuator>
</mujoco>"""

SLIDER = """<mujoco model="slider">
  <option timestep="0.002"/>
  <worldbody>
    <body name="cart">
      <joint name="rail" type="slide" axis="1 0 0" damping="1" {truth}/>
      <geom type="box" size="0.05 0.05 0.02" mass="1"/>
    </body>
  </worldbody>
  <actuator><motor name="f" joint="rail" ctrlrange="-10 10"/></actuator>
</mujoco>"""

# the servo arm stepped at 1 ms, a hand on a wrist that a stiff position servo holds at 0 (it sits
# within its noise); the truth's friction at the shoulder
HELD_WRIST = SERVO_ARM.replace('timestep="0.002" integrator="implicit"', 'timestep="0.001" integrator="implicitfast"').replace(
    "{truth}", '<body name="hand" pos="0 0 -0.25"><joint name="wrist" axis="1 0 0" damping="0.05"/>'
    '<geom type="box" size="0.03 0.03 0.02" mass="0.1"/></body>').replace(
    '<joint name="shoulder" axis="0 1 0" damping="0.1"/>', '<joint name="shoulder" axis="0 1 0" damping="0.1" {truth}/>').replace(
    "</actuator>", '<position name="hold" joint="wrist" kp="30" kv="0.5" ctrlrange="-0.0001 0.0001"/></actuator>')

# name: (model text, the truth (an attribute string for {truth}, or ""), words, drive, extras):
#   drive: "multisine" (ctrl), "steps" (random steps in ctrl), "swing" (released, no actuator),
#     "sine" (one sine of 0.7 Hz at 0.8 of the command range: the test a lab runs first);
#   extras: delay_s (the command reaches the plant this late), offset (added to the logged angle),
#   plant_dt (the true plant stepped at this, not the model's step), period (log period, s),
#   jitter (each position sample taken up to this many physics steps off its instant, its time stamped so),
#   lag_s (the command reaches the actuator through a first-order lag of this time constant),
#   count, seconds (recordings and their length: 3 of 8 s), qfrc (a function of (qpos, qvel) giving
#   a joint force applied at every physics step: physics the library has no name for, written here),
#   plant (the truth's own MJCF, with bodies and joints the model lacks; the model's joints are
#   logged, its actuators' names driven), excite (per recording, which actuators are driven; the
#   others held at the centre of their range), around ((pose, amplitude): the drive's range, the
#   joints starting at the pose; for position servos whose ctrlrange is the joints' whole range),
#   qpos0 (the joints' start where the pose is not given in joint coordinates), noise (the
#   positions' noise std, 1e-3), rest (driven this many seconds, then held at the
#   range's centre as long, in turn)
PROBES = {
    "flywheel_intvelocity_friction": (FLYWHEEL, 'frictionloss="0.05"', "coulomb_friction@spin 0.05 N m",
                                      "multisine", {}),
    "servo_arm_general_payload": (SERVO_ARM, '<geom type="sphere" pos="0 0 -0.25" size="0.01" mass="0.15"/>',
                                  "mass_offset@lower 0.15 kg at its tip", "steps", {}),
    "axis_position_kv_delay": (AXIS, "", "action_delay 0.012 s", "steps", {"delay_s": 0.012}),
    "ball_free_swing_damping": (BALL, 'damping="0.004"', "viscous_damping@ball 0.004 N m s/rad", "swing", {}),
    "pendulum_joint_force_limit": (PENDULUM, 'actuatorfrcrange="-0.6 0.6"',
                                   "saturation@m 0.6 N m (the joint's actuatorfrcrange)", "multisine", {}),
    "arm_held_wrist_friction": (HELD_WRIST, 'frictionloss="0.6"', "coulomb_friction@shoulder 0.6 N m (the wrist "
                                "held still)", "multisine", {}),
    "gravcomp_arm_damping": (GRAVCOMP, 'damping="0.15"', "viscous_damping@j1 0.15 N m s/rad", "multisine", {}),
    "pendulum_encoder_offset": (PENDULUM, "", "sensor_offset@hinge 0.05 rad", "multisine", {"offset": 0.05}),
    "pendulum_jittered_log_friction": (PENDULUM, 'frictionloss="0.08"', "coulomb_friction@hinge 0.08 N m (each sample "
                                       "taken up to 1 ms off its 5 ms instant, stamped so)", "multisine", {"jitter": 1}),
    "slider_logged_1khz_damping": (SLIDER, 'frictionloss="0.8"', "coulomb_friction@rail 0.8 N (log at 1 kHz, "
                                   "model step 2 ms)", "steps", {"plant_dt": 0.0005, "period": 0.001}),
}


def record(name, text, truth, drive, extras, work):
    nominal = os.path.join(work, f"{name}.xml")
    for fname, content in extras.get("files", {}).items():  # what the model refers to (mesh files)
        open(os.path.join(work, fname), "w").write(content)
    open(nominal, "w").write(text.format(truth=""))
    plant = os.path.join(work, f".{name}_plant.xml")  # (a file: mesh paths are relative to it)
    open(plant, "w").write(extras.get("plant") or text.format(truth=truth))
    m = mujoco.MjModel.from_xml_path(plant)
    mn = mujoco.MjModel.from_xml_path(nominal)  # what is logged: the nominal model's joints
    adr = [m.jnt_qposadr[m.joint(mn.joint(j).name).id] for j in range(mn.njnt)]   # (in the plant's qpos)
    logged = np.concatenate([np.arange(a, a + (4 if mn.jnt_type[j] == 1 else 1)) for j, a in enumerate(adr)])
    if "plant_dt" in extras:
        m.opt.timestep = extras["plant_dt"]
    sub = int(round(extras.get("period", 0.005) / m.opt.timestep))
    period = sub * m.opt.timestep  # the samples' true spacing (4 ms for a 2 ms step)
    lag = int(round(extras.get("delay_s", 0.0) / m.opt.timestep))  # a delay line at the plant's step
    rng = np.random.default_rng(1)
    lo, hi = m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1]
    if "around" in extras:  # the drive within +-amplitude of a pose, not over the whole ctrlrange
        centre, amplitude = (np.asarray(v, float) for v in extras["around"])
        lo, hi = centre - amplitude, centre + amplitude
    paths = []
    for r in range(extras.get("count", 3)):
        d = mujoco.MjData(m)
        if "around" in extras:  # (starting there; ``qpos0`` where the joints are not the actuators' coordinates)
            q0 = np.asarray(extras.get("qpos0", centre), float)
            d.qpos[:len(q0)] = q0
            d.ctrl[:] = centre
        if drive == "swing":  # tilted and pushed sideways: a conical swing
            mujoco.mju_axisAngle2Quat(d.qpos[:4], np.array([1.0, 0.3, 0.0]) / np.hypot(1, 0.3), 0.6 + 0.2 * r)
            d.qvel[:3] = [0.0, 0.0, 1.5 - r]
        mujoco.mj_forward(m, d)
        freqs, phases = rng.uniform(0.2, 3, (max(m.nu, 1), 5)), rng.uniform(0, 6.28, (max(m.nu, 1), 5))
        levels = rng.uniform(-1, 1, (400, max(m.nu, 1)))
        cols = []
        for j in range(mn.njnt):
            jn = mn.joint(j).name
            cols += [f"qpos:{jn}:{c}" for c in "qw qx qy qz".split()] if mn.jnt_type[j] == 1 else [f"qpos:{jn}"]
        cols += [f"ctrl:{m.actuator(a).name}" for a in range(m.nu)]
        queue = [d.ctrl.copy()] * lag
        rows, qs = [], [d.qpos.copy()]  # qs: the state at every physics step (a jittered logger samples it)
        jit = np.random.default_rng(10 + r).integers(-extras.get("jitter", 0), extras.get("jitter", 0) + 1,
                                                     int(extras.get("seconds", 8.0) / period) + 1)
        u_eff = d.ctrl.copy()  # the command the actuator acts on: lagged at the plant's step (``lag_s``)
        for k in range(int(extras.get("seconds", 8.0) / period)):
            t = k * period
            if drive == "multisine":
                u = np.sin(2 * np.pi * freqs * t + phases).sum(1) / 2.5
                cmd = np.clip((lo + hi) / 2 + u * (hi - lo) / 2, lo, hi)
            elif drive == "sine":
                cmd = (lo + hi) / 2 + 0.8 * np.sin(2 * np.pi * 0.7 * t + r) * (hi - lo) / 2
            elif drive == "steps":
                cmd = (lo + hi) / 2 + levels[int(t / 0.25), :m.nu] * (hi - lo) / 2 * 0.8
            else:
                cmd = np.zeros(0)
            if "rest" in extras and int(t / extras["rest"]) % 2:  # driven, then resting, in turn
                cmd = (lo + hi) / 2
            if "excite" in extras:  # one actuator at a time: the others held at their range's centre
                cmd = np.where(extras["excite"][r], cmd, (lo + hi) / 2)
            rows.append([t + 1.5, *rng.normal(0, extras.get("noise", 1e-3), len(logged)), *cmd])
            for _ in range(sub):
                queue.append(cmd)
                u_eff = u_eff + (queue.pop(0) - u_eff) * (1 - np.exp(-m.opt.timestep / extras.get("lag_s", 1e-12)))
                d.ctrl[:] = u_eff
                if "qfrc" in extras:  # a joint force written here, from the state it acts in
                    d.qfrc_applied[:] = extras["qfrc"](d.qpos, d.qvel)
                mujoco.mj_step(m, d)
                qs.append(d.qpos.copy())
        for k, row in enumerate(rows):  # the positions, each taken jit[k] physics steps off its instant
            i = min(max(k * sub + jit[k], 0), len(qs) - 1)
            row[0] += (i - k * sub) * m.opt.timestep
            row[1:1 + len(logged)] += qs[i][logged] + np.eye(len(logged))[0] * extras.get("offset", 0.0)
        if "drop" in extras:  # samples a logger lost: (first row, count) left out of the file
            first, count = extras["drop"]
            rows = rows[:first] + rows[first + count:]
        paths.append(os.path.join(work, f"{name}_{r}.csv"))
        np.savetxt(paths[-1], np.array(rows), delimiter=",", header="time," + ",".join(cols), comments="")
    return nominal, paths


def main(work, only=()):
    os.makedirs(work, exist_ok=True)
    print("| probe | truth | named | values | held-out NRMSE before -> after | seconds |")
    print("|---|---|---|---|---|---|")
    for name, (text, truth, words, drive, extras) in PROBES.items():
        if only and name not in only:
            continue
        nominal, paths = record(name, text, truth, drive, extras, work)
        diagnose_and_print(name, words, nominal, paths, work)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/new_user_probes_2", tuple(sys.argv[2:]))
