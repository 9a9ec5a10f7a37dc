"""Time one prediction call with and without the replay that leaves out a backlash no physics of
the call has (``Effects.skippable``), in one process, alternating (the 2-core machine's speed drifts
by 20% within minutes, so runs minutes apart cannot be compared).

    python ab_replay.py CASE_FOLDER [HORIZON=25]

``CASE_FOLDER``: one case as ``diagnosis_independent.py`` writes it under ``work=`` (``nominal.xml``,
``train_0.csv``, ``train_1.csv``, ``heldout.csv``). Two ``Shooting``s of the same recordings (the
physics step the model's, as ``System`` chooses it), the second with ``skippable`` emptied (the
code before); 8 physics per call, all at the model's values ("plain") or with a motor lag of 20 ms
on the first actuator ("lag"); 5 rounds of 10 calls each, median ms per call.
"""
import math
import sys
import time

import numpy as np

from sim2real.sysid.recordings import load_all
from sim2real.sysid.diagnose import _model_for_loading
from sim2real.sysid.shooting import Shooting
from sim2real.sysid.system import System
from sim2real.sysid.trajectory import from_recording


def main(folder, horizon=25):
    model = f"{folder}/nominal.xml"
    recs = load_all([f"{folder}/{n}.csv" for n in ("train_0", "train_1", "heldout")], _model_for_loading(model), "x")
    dt = recs[0].dt

    def build(skip):
        system = System(model, dt=dt, max_delay=max(16, int(math.ceil(0.12 / dt))))
        if not skip:
            system.effects.skippable = ()
        return system, Shooting(system, [from_recording(r, system, None) for r in recs], int(horizon), heldout=(2,))

    (system, new), (_, old) = build(True), build(False)
    spec = system.spec
    lag = [n for n in spec.names if n.startswith("motor_lag:")][0]
    plain = np.tile(spec.default.astype(np.float32), (8, 1))
    lagged = plain.copy()
    lagged[:, spec.index(lag)] = 0.02
    v0 = np.tile(new.v0[None], (8, 1, 1)).astype(np.float32)
    tiles = new.tiles.of("fit")
    print(f"{folder}: nu {system.mj.nu}, segments per call {new.Sc}, physics steps per sample {new.n}")
    for zs in (plain, lagged):   # compile, and the two replays give the same predictions
        a, b = new.predict(zs, v0, tiles), old.predict(zs, v0, tiles)
        assert all(np.array_equal(a[k], b[k]) for k in a)
    ms = {}
    for _ in range(5):
        for name, sh in (("skip", new), ("full", old)):
            for zn, zs in (("plain", plain), ("lag", lagged)):
                t = time.perf_counter()
                for _ in range(10):
                    sh.predict(zs, v0, tiles)
                ms.setdefault((zn, name), []).append((time.perf_counter() - t) / 10 * 1e3)
    for (zn, name), v in sorted(ms.items()):
        print(f"  {zn:5s} {name}: {np.median(v):.1f} ms per call")


if __name__ == "__main__":
    main(*sys.argv[1:])
