"""A plain rich progress bar for the loops of the scripts (fits, evaluation, recording).

The training driver has its own bar (steps/s and return columns, ``sim2real.training.runs.Progress``).
"""
from __future__ import annotations


class Bar:
    """``Bar(enabled, total, label, done=0)``; ``step(n, text)`` advances and relabels; ``close()``.

    A disabled bar (``progress=false``, tests) does nothing, so callers need no branches.
    Also a context manager (closes on exit, errors included).
    """

    def __init__(self, enabled: bool, total: int, label: str, done: int = 0):
        self.enabled = bool(enabled)
        if self.enabled:
            from rich.progress import Progress

            self.p = Progress()
            self.p.start()
            self.t = self.p.add_task(label, total=total, completed=done)

    def step(self, n: int = 1, text: str | None = None):
        # every step is a safe point for a SIGTERM that was swallowed where it landed
        from sim2real.common.cli import raise_if_terminated

        raise_if_terminated()
        if self.enabled:
            self.p.update(self.t, advance=n, **({"description": text} if text is not None else {}))

    def close(self):
        if self.enabled:
            self.p.stop()
            self.enabled = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
