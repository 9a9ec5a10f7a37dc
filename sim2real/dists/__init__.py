"""Distributions over physics sub-vectors: pytrees with the same four functions.

``sample(key, d, n)``, ``log_prob(d, z)``, ``kl(p, q)``, ``entropy(d)`` dispatch on the type of
``d``: :class:`~sim2real.dists.uniform.Uniform`, :class:`~sim2real.dists.binned.Binned`,
:class:`~sim2real.dists.gaussian.Gaussian`, :class:`~sim2real.dists.beta.Beta`. Being pytrees of arrays, they can be differentiated
(LSDR), vmapped, or updated in closed form (REPS).
"""
from sim2real.dists import beta, binned, gaussian, uniform

_MODULES = {uniform.Uniform: uniform, binned.Binned: binned, gaussian.Gaussian: gaussian, beta.Beta: beta}


def module_of(d):
    try:
        return _MODULES[type(d)]
    except KeyError:
        raise TypeError(f"not a sim2real distribution: {type(d).__name__}") from None


def sample(key, d, n=None):
    return module_of(d).sample(key, d, n)


def log_prob(d, z):
    return module_of(d).log_prob(d, z)


def kl(p, q):
    if type(p) is not type(q):
        raise TypeError(f"kl between {type(p).__name__} and {type(q).__name__}: use kl_from_uniform")
    return module_of(p).kl(p, q)


def entropy(d):
    return module_of(d).entropy(d)


def kl_from_uniform(low, high, d):
    """KL(U(low, high) || d): LSDR's regulariser against the wide prior box."""
    if isinstance(d, uniform.Uniform):
        return uniform.kl(uniform.make(low, high), d)
    return module_of(d).kl_from_uniform(low, high, d)
