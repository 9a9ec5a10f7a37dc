"""Minimal reproducer: an MJX step split over 2 GPUs, plain mujoco + mujoco.mjx + JAX (no sim2real).

    CUDA_VISIBLE_DEVICES=0,1 python benchmarks/xla_multigpu_repro.py mode=shard_map model=hopper

mode: shard_map (jax.shard_map over a 1-D mesh), jit_sharded (jit with NamedSharding inputs, XLA's
partitioner), single (one device). model: pendulum (no contacts), hopper (sim2real's asset:
contacts, the constraint solver's while loop), or arith / while (no MJX: a fori_loop of
arithmetic, a data-dependent while_loop). loop: fori, scan or none (one MJX step).
check_vma: shard_map's varying-axes check. Prints 'ok' with the result's checksum.
"""
from __future__ import annotations

import dataclasses
import os
import sys
from typing import Literal

import jax
import jax.numpy as jnp
import mujoco
from jax.sharding import Mesh, NamedSharding, PartitionSpec as P
from mujoco import mjx

from sim2real.common.cli import settings  # the key=value parsing only; the program is plain MJX

PENDULUM = """<mujoco><option timestep="0.002"/><worldbody><body><joint name="j" type="hinge" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.05" mass="1"/></body></worldbody>
<actuator><motor joint="j"/></actuator></mujoco>"""


@dataclasses.dataclass
class Settings:
    """mode, model, loop, check_vma: as the module says; batch: envs; steps: MJX steps."""
    mode: Literal["shard_map", "jit_sharded", "single"] = "shard_map"
    model: Literal["hopper", "pendulum", "arith", "while"] = "hopper"
    loop: Literal["fori", "scan", "none"] = "fori"
    check_vma: bool = False
    batch: int = 8192
    steps: int = 20


def main(a: Settings):
    mode, model, batch, steps, loop = a.mode, a.model, a.batch, a.steps, a.loop
    if model in ("arith", "while"):  # no MJX at all
        def roll(x, u):
            if model == "arith":
                return jax.lax.fori_loop(0, steps, lambda i, x: jnp.sin(x) * 0.9 + u, x)
            return jax.vmap(lambda x0, u0: jax.lax.while_loop(lambda c: c[1] < steps + (c[0][0] > 0),
                                                             lambda c: (jnp.sin(c[0]) * 0.9 + u0, c[1] + 1),
                                                             (x0, 0))[0])(x, u)
        m = mujoco.MjModel.from_xml_string(PENDULUM)
    elif model == "hopper":
        m = mujoco.MjModel.from_xml_path(os.path.join(os.path.dirname(__file__), "..", "sim2real", "envs", "assets", "hopper.xml"))
    else:
        m = mujoco.MjModel.from_xml_string(PENDULUM)
    mx = mjx.put_model(m)
    d0 = mjx.make_data(mx)

    def mjx_roll(qpos, ctrl):
        def one(q, u):
            d = d0.replace(qpos=q, ctrl=u)
            if loop == "fori":
                d = jax.lax.fori_loop(0, steps, lambda i, d: mjx.step(mx, d), d)
            elif loop == "scan":
                d = jax.lax.scan(lambda d, _: (mjx.step(mx, d), None), d, None, length=steps)[0]
            else:  # one step, no loop
                d = mjx.step(mx, d)
            return d.qpos
        return jax.vmap(one)(qpos, ctrl)

    if model not in ("arith", "while"):
        roll = mjx_roll

    k1, k2 = jax.random.split(jax.random.PRNGKey(0))
    qpos = jnp.tile(jnp.asarray(m.qpos0), (batch, 1)) + 0.01 * jax.random.normal(k1, (batch, m.nq))
    ctrl = jax.random.uniform(k2, (batch, m.nq if model in ("arith", "while") else m.nu), minval=-1, maxval=1)
    devs = jax.devices()
    print("devices", devs, "jax", jax.__version__, "mujoco", mujoco.__version__, flush=True)
    mesh = Mesh(devs, ("b",))
    if mode == "shard_map":
        f = jax.jit(jax.shard_map(roll, mesh=mesh, in_specs=(P("b"), P("b")), out_specs=P("b"),
                                    check_vma=a.check_vma))
        args = jax.device_put((qpos, ctrl), NamedSharding(mesh, P("b")))
    elif mode == "jit_sharded":
        f = jax.jit(roll)
        args = jax.device_put((qpos, ctrl), NamedSharding(mesh, P("b")))
    else:
        f = jax.jit(roll)
        args = (qpos, ctrl)
    print("compiling", mode, model, flush=True)
    out = f(*args).block_until_ready()
    print("ok", mode, model, float(jnp.sum(out)), flush=True)


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
