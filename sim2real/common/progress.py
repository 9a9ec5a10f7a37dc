"""A plain rich progress bar for the loops of the scripts (fits, evaluation, recording).

The training driver has its own bar (steps/s and return columns, ``sim2real.training.runs.Progress``).
"""
from __future__ import annotations

import time


class Bar:
    """``Bar(enabled, total, label, done=0)``; ``step(n, text)`` advances and relabels; ``close()``.

    A disabled bar (``progress=false``, tests) does nothing, so callers need no branches.
    Also a context manager (closes on exit, errors included).

    Where the output is not a terminal (a log file, a batch job) rich draws nothing until the
    bar stops, so a long run looked dead: there each new stage (a step that advances) and each
    relabel at most every ``quiet_s`` seconds prints one plain line, with the elapsed time.
    """

    quiet_s = 10.0

    def __init__(self, enabled: bool, total: int, label: str, done: int = 0):
        self.enabled = bool(enabled)
        if self.enabled:
            from rich.progress import Progress

            self.p = Progress()
            self.plain = not self.p.console.is_terminal
            self.label, self.total, self.done = label, total, done
            self.t0 = self.last = time.monotonic()
            self.p.start()
            self.t = self.p.add_task(label, total=total, completed=done)

    def step(self, n: int = 1, text: str | None = None):
        # every step is a safe point for a SIGTERM that was swallowed where it landed
        from sim2real.common.cli import raise_if_terminated

        raise_if_terminated()
        if self.enabled:
            self.p.update(self.t, advance=n, **({"description": text} if text is not None else {}))
            self.done += n
            if self.plain and text is not None:
                now = time.monotonic()
                if n > 0 or now - self.last >= self.quiet_s:
                    self.last = now
                    print(f"[{now - self.t0:7.1f} s] {self.label} {self.done}/{self.total}: {text}", flush=True)

    def close(self):
        if self.enabled:
            self.p.stop()
            self.enabled = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
