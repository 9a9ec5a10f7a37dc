"""A changed size or density changes mass, centre of mass and inertia as MuJoCo's compiler does."""
import os

import mujoco
import numpy as np
import pytest

from conftest import env_for
from sim2real.envs.base import ASSETS
from sim2real.physics.model_apply import to_mjmodel


def compiled_with(xml, geom, radius, density_factor):
    spec = mujoco.MjSpec.from_file(os.path.join(ASSETS, xml))
    spec.geom(geom).size[0] = radius
    for g in spec.geoms:
        if g.name != "floor":
            g.density = g.density * density_factor
    return spec.compile()


def full_inertia(m, b):
    r = np.zeros(9)
    mujoco.mju_quat2Mat(r, m.body_iquat[b])
    r = r.reshape(3, 3)
    return r @ np.diag(m.body_inertia[b]) @ r.T


@pytest.mark.parametrize("radius,factor", [(0.1, 1.0), (0.02, 3.0), (0.3, 0.2)])
def test_hopper_torso_size_and_density_match_compiler(radius, factor):
    env = env_for("hopper")
    ref = compiled_with("hopper.xml", "torso_geom", radius, factor)
    mine = to_mjmodel(env.physics, env.z_of(torso_size=radius, density=1000.0 * factor))
    np.testing.assert_allclose(mine.body_mass, ref.body_mass, rtol=1e-5)
    np.testing.assert_allclose(mine.body_ipos, ref.body_ipos, atol=1e-6)
    for b in range(1, ref.nbody):  # single-geom bodies: exact, frame included
        np.testing.assert_allclose(full_inertia(mine, b), full_inertia(ref, b), rtol=1e-4, atol=1e-7)
    assert mine.body_mass[1] != pytest.approx(env.mj_model.body_mass[1])


@pytest.mark.parametrize("radius", [0.1, 0.01])
def test_cheetah_two_geom_torso_rotates_principal_frame(radius):
    """torso + head: the principal frame turns with the size; the full tensor still matches."""
    env = env_for("halfcheetah")
    rho0 = env.spec["density"].default
    ref = compiled_with("halfcheetah.xml", "torso", radius, 1.0)
    mine = to_mjmodel(env.physics, env.z_of(torso_size=radius, density=rho0))
    np.testing.assert_allclose(mine.body_mass, ref.body_mass, rtol=1e-5)
    np.testing.assert_allclose(mine.body_ipos[1], ref.body_ipos[1], atol=1e-6)
    np.testing.assert_allclose(full_inertia(mine, 1), full_inertia(ref, 1), rtol=1e-4, atol=1e-6)
