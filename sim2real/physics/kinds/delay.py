"""Action delay, in control steps (fractional steps are exact; ``Effects.delayed`` runs the delay line)."""
from __future__ import annotations

from sim2real.physics.kinds.base import Kind


class ActionDelay(Kind):
    owns = ("action_delay",)
    order = 70
    effect = "action_delay"

    def candidates(self, system, sc, add, target) -> None:
        if not system.mj.nu:
            return
        pts = [d for d in (0.4, 1.0, 2.0, 3.5, 6.0, 10.0, 17.0, 28.0, 45.0, 70.0) if d <= sc.max_delay - 1]
        add("action_delay", "", ["action_delay"], [(d,) for d in pts], [1.0], [(0.1, float(max(pts)))])
