"""sim2real: JAX-native, massively batched sim-to-real training and sim-vs-real diagnosis."""
import logging as _logging

# mujoco.mjx tries to import the optional Warp backend and logs a failure on every import;
# the JAX backend is what this package uses, so keep that line out of users' terminals.
_logging.getLogger("mujoco.mjx").setLevel(_logging.ERROR)

__version__ = "0.1.0"
