"""XLA CPU slowdown exponential in a kinematic chain's depth: plain mujoco.mjx + JAX, no sim2real.

    python benchmarks/xla_cpu_chain_repro.py emitters=true    # XLA's default
    python benchmarks/xla_cpu_chain_repro.py emitters=false   # what import sim2real sets on jaxlib 0.9

A serial chain of n hinge links (inertials only, no geoms, no contacts), 64 copies vmapped:
milliseconds per call of ``mjx.kinematics`` and of ``mjx.step`` after compilation; only MJX and
JAX run (sim2real parses the settings). ``XLA_FLAGS`` is written before JAX starts its backends,
so ``sim2real/_xla_cpu.py``'s own setting does not apply. Prints one CSV row per (n, function);
the results of one run of each are in ``results/xla_cpu_chain.csv``.
"""
from __future__ import annotations

import dataclasses
import os
import sys
import time

import jax
import jax.numpy as jnp
import mujoco
from mujoco import mjx
from mujoco.mjx._src import smooth

from sim2real.common.cli import settings


@dataclasses.dataclass
class Settings:
    """emitters: XLA's CPU fusion emitters on (XLA's default) or off; envs: copies vmapped."""
    emitters: bool = True
    envs: int = 64


def chain(n: int) -> mujoco.MjModel:
    links = "".join('<body pos="0 0 0.2"><joint axis="0 1 0"/>'
                    '<inertial pos="0 0 0.1" mass="1" diaginertia="0.01 0.01 0.001"/>' for _ in range(n))
    return mujoco.MjModel.from_xml_string(f"<mujoco><worldbody>{links}{'</body>' * n}</worldbody></mujoco>")


def ms_per_call(fn, mx, ds, reps: int = 5) -> float:
    f = jax.jit(jax.vmap(lambda d: fn(mx, d)))
    jax.block_until_ready(f(ds))
    t = time.perf_counter()
    for _ in range(reps):
        r = f(ds)
    jax.block_until_ready(r)
    return (time.perf_counter() - t) / reps * 1e3


def main(a: Settings):
    os.environ["XLA_FLAGS"] = f"--xla_cpu_use_fusion_emitters={str(a.emitters).lower()}"
    print(f"# jax {jax.__version__}, XLA_FLAGS={os.environ['XLA_FLAGS']!r}, {a.envs} envs vmapped, CPU")
    print("links,function,ms_per_call")
    for n in (3, 4, 5, 6, 7):
        m = chain(n)
        mx = mjx.put_model(m)
        d = mjx.make_data(mx)
        ds = jax.vmap(lambda q: d.replace(qpos=q))(jnp.tile(jnp.asarray(m.qpos0), (a.envs, 1)))
        for name, fn in (("kinematics", smooth.kinematics), ("step", mjx.step)):
            print(f"{n},{name},{ms_per_call(fn, mx, ds):.3f}", flush=True)


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
