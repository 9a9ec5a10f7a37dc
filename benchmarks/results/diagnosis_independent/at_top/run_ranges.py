"""``heldout_segments/run_device.py`` with every case's candidate search ranges logged
(``OUT/ranges.jsonl``: case label, then per candidate label its first parameter's range), so that
the rows' fitted first parameters can be set against the edges of their ranges offline: where a
fit that ``select._at_edge`` does not widen (a friction, damping, stiffness, drag or offset) ends
at its range's top. Nothing in the diagnosis changes. Same arguments and environment:

    CASES=... python run_ranges.py OUT SECONDS [LIST ...]
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "heldout_segments"))
import run_device  # noqa: E402

from sim2real.sysid import select as S  # noqa: E402

LOG = os.path.join(sys.argv[1], "ranges.jsonl")
_init = S.Selector.__init__


def init(self, fitter, nominal, candidates, cfg, *a, **k):
    with open(LOG, "a") as f:
        f.write(json.dumps({"case": run_device.CURRENT["label"],
                            "ranges": {c.label: [float(c.search[0][0]), float(c.search[0][1])] for c in candidates}})
                + "\n")
    _init(self, fitter, nominal, candidates, cfg, *a, **k)


S.Selector.__init__ = init

if __name__ == "__main__":
    run_device.cli()
