"""``heldout_segments/run_device.py`` with every fit whose start lies outside its range logged
(``OUT/oob.txt``: case label, parameter, start, range): where the start clip of ``Fitter.fit``
(this session's fix) can change what a case computes. Same arguments and environment."""
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "heldout_segments"))
import run_device  # noqa: E402

from sim2real.sysid import fit as F  # noqa: E402

LOG = os.path.join(sys.argv[1], "oob.txt")
_fit = F.Fitter.fit


def fit(self, z0, v0, names, tiles, iters=6, tol=1e-3, bounds=None, at_noise=False):
    idx, lo, hi = self.range_of(names, bounds)
    z = np.asarray(z0, float)[idx]
    with open(LOG, "a") as f:
        for k, n in enumerate(names):
            if not lo[k] - 1e-9 * max(1.0, abs(hi[k])) <= z[k] <= hi[k] + 1e-9 * max(1.0, abs(hi[k])):
                f.write(f"{run_device.CURRENT['label']} {n} {z[k]:.6g} {lo[k]:.6g} {hi[k]:.6g}\n")
    return _fit(self, z0, v0, names, tiles, iters, tol, bounds, at_noise)


F.Fitter.fit = fit

if __name__ == "__main__":
    run_device.cli()
