"""XLA CPU slowdown exponential in a kinematic chain's depth: plain mujoco.mjx + JAX, no sim2real.

    python benchmarks/xla_cpu_chain_repro.py                 # as installed
    XLA_FLAGS=--xla_cpu_use_fusion_emitters=false python benchmarks/xla_cpu_chain_repro.py

A serial chain of n hinge links (inertials only, no geoms, no contacts), 64 copies vmapped:
milliseconds per call of ``mjx.kinematics`` and of ``mjx.step`` after compilation. sim2real sets
the flag itself on jaxlib 0.9 (``sim2real/_xla_cpu.py``), so this script must not import it.
Prints one CSV row per (n, function); the results of one run are committed next to it
(``results/xla_cpu_chain.csv``).
"""
from __future__ import annotations

import os
import sys
import time

import jax
import jax.numpy as jnp
import mujoco
from mujoco import mjx
from mujoco.mjx._src import smooth

assert "sim2real" not in sys.modules


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


def main():
    print(f"# jax {jax.__version__}, XLA_FLAGS={os.environ.get('XLA_FLAGS', '')!r}, 64 envs vmapped, CPU")
    print("links,function,ms_per_call")
    for n in (3, 4, 5, 6, 7):
        m = chain(n)
        mx = mjx.put_model(m)
        d = mjx.make_data(mx)
        ds = jax.vmap(lambda q: d.replace(qpos=q))(jnp.tile(jnp.asarray(m.qpos0), (64, 1)))
        for name, fn in (("kinematics", smooth.kinematics), ("step", mjx.step)):
            print(f"{n},{name},{ms_per_call(fn, mx, ds):.3f}", flush=True)


if __name__ == "__main__":
    main()
