"""Why chain 1 of ``seed2/`` failed after one loop (530 on the real plant) although its diagnosis
named the plant's shared 40 ms lag: its policy (``seed1_centred/``) on the native-MuJoCo plant and
on the MJX env with the plant's physics, and on variants of each (the limbs at the masses the
diagnosis re-fitted lighter; no observation noise; the plant's filters with ``actearly``, driving
the force in the physics step the command arrives as the env's lag does, where MuJoCo's default
drives it one 2 ms step later, and that with MuJoCo's own 2 ms actuator delay added back; the env
with an action delay of 1 and 2 ms). 2-core CPU, a minute.

    python benchmarks/results/closed_loop_warm_std_hopper/seed2/native_vs_mjx.py [episodes=16]
"""
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", "..", ".."))
sys.path.insert(0, ROOT)

from sim2real.tools.record import from_run  # noqa: E402

PLANT = os.path.join(ROOT, "benchmarks", "plants", "hopper_real.xml")
LAGS = "motor_lag:thigh=0.04,motor_lag:leg=0.04,motor_lag:foot=0.04"  # the plant's filterexact 40 ms


def _plant_with(masses: dict[str, float], folder: str, early: bool = False, delay: float = 0.0) -> str:
    """The real plant's MJCF with these geoms' masses (kg) set (their inertia scales with them);
    ``early``: its motors' filters drive the force in the step the command arrives (``actearly``);
    ``delay``: and MuJoCo's own actuator delay (s) on each motor."""
    xml = open(PLANT).read()
    for geom, m in masses.items():
        xml = xml.replace(f'name="{geom}" ', f'name="{geom}" mass="{m:.6f}" ', 1)
    if early:
        more = f' delay="{delay}" nsample="3"' if delay else ""
        xml = xml.replace('dynprm="0.04"', f'dynprm="0.04" actearly="true"{more}')
    path = os.path.join(folder, f"hopper_real_{len(masses)}_{int(early)}_{delay}.xml")
    with open(path, "w") as f:
        f.write(xml)
    return path


def main(episodes: int = 16) -> None:
    import tempfile

    run = os.path.join(HERE, "seed1_centred")
    fp = json.load(open(os.path.join(HERE, "seed1", "diagnosis.json")))["fitted_params"]
    fitted = {b: fp[f"mass:{b}"] for b in ("thigh", "leg", "foot")}  # kg, the re-fitted limbs
    limbs = {f"{b}_geom": m for b, m in fitted.items()}
    with tempfile.TemporaryDirectory() as tmp:
        cases = [("native plant (noise 1e-3, as scored)", PLANT, 1e-3),
                 ("native plant, no observation noise", PLANT, 0.0),
                 ("native plant, limbs at the fitted masses", _plant_with(limbs, tmp), 1e-3),
                 ("native plant, its filters with actearly", _plant_with({}, tmp, early=True), 1e-3),
                 ("native plant, actearly and a 2 ms actuator delay (MuJoCo's own)",
                  _plant_with({}, tmp, early=True, delay=0.002), 1e-3),
                 ("MJX env, payload:torso=1.5 + the 40 ms lags", f"payload:torso=1.5,{LAGS}", 0.0),
                 ("MJX env, the same with the limbs at the fitted masses",
                  f"payload:torso=1.5,{LAGS}," + ",".join(f"mass:{b}={m}" for b, m in fitted.items()),
                  0.0)]
        # (the env's action_delay counts 8 ms control steps: 0.125 and 0.25 are 1 and 2 ms)
        cases += [(f"MJX env, payload + lags + an action delay of {8 * d:g} ms",
                   f"payload:torso=1.5,{LAGS},action_delay={d}", 0.0) for d in (0.125, 0.25)]
        print(f"chain 1's first-loop policy, {episodes} episodes each (seed 12345):")
        for name, target, noise in cases:
            r, _ = from_run(run, target, episodes, seed=12345, run_seed=0, noise=noise)
            print(f"  {name}: mean {np.mean(r.ret):.1f}, min {np.min(r.ret):.1f}, max {np.max(r.ret):.1f}", flush=True)


if __name__ == "__main__":
    main(*[int(a.split("=", 1)[1]) for a in sys.argv[1:2]])
