"""Smoothed derivatives of sampled positions (Savitzky-Golay) and MuJoCo's velocity state."""
from __future__ import annotations


def velocity_state(dq, ddq, timestep: float, rk4: bool = False):
    """Central-difference velocity -> the velocity *state* of MuJoCo's integrator.

    Semi-implicit Euler (and the implicit variants) update the velocity first and then the
    position with it, so the velocity held in ``qvel`` after a step is the mean velocity of the
    step just taken: the smooth velocity half a step earlier, ``dq - h/2 * ddq`` (physics step
    ``h``). Starting a simulation from the central-difference velocity instead starts it half a
    step ahead, a bias that a fit would blame on the physics. RK4's state is the continuous one.
    All arrays broadcast; returns the state.
    """
    return dq if rk4 else dq - 0.5 * timestep * ddq
