"""Shared command-line plumbing: clean one-line errors, non-zero exit codes, clean stops.

Exit status: 0 done, 2 bad input (the message names the file, column, row or key), 130 stopped by
Ctrl-C or SIGTERM (after the tool cleaned up: temporary folders removed, a training run's
checkpoint kept).
"""
from __future__ import annotations

import contextlib
import signal
import sys
import threading

INTERRUPTED = 130


class Stopped(Exception):
    """A long job stopped at a safe point on request (SIGINT/SIGTERM); the message says what was kept."""


class StopRequest:
    """Set by SIGINT/SIGTERM while a long job runs (see :func:`stop_on_signal`)."""

    def __init__(self):
        self.requested = False
        self.signal_name = ""


@contextlib.contextmanager
def stop_on_signal():
    """Turn the first SIGINT/SIGTERM into a flag the job checks at its next safe point; a second
    one stops at once (KeyboardInterrupt). Off the main thread (no handlers there) the flag
    never rises and signals keep their default behaviour.

    Why a flag: a KeyboardInterrupt raised wherever Python happens to be (inside orbax's
    asynchronous checkpoint writer, a JAX callback, an event loop) can be swallowed there, and the
    run then goes on to the end and exits 0.
    """
    req = StopRequest()
    if threading.current_thread() is not threading.main_thread():
        yield req
        return

    def handler(signum, frame):
        if req.requested:
            raise KeyboardInterrupt
        req.requested = True
        req.signal_name = signal.Signals(signum).name
        print(f"\n{req.signal_name}: stopping at the next safe point (again to stop at once)", file=sys.stderr)

    old = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield req
    finally:
        for s, h in old.items():
            signal.signal(s, h)


_TERMINATED = False
# Seconds a SIGTERM'd tool has to unwind before it is ended from a watchdog thread. A Python signal
# handler runs only between bytecodes: a long XLA compile or jitted call delays it, and an
# interrupt raised inside a library's callback or lock can be swallowed or leave the interpreter
# hung at exit. A scheduler sends SIGKILL after its own grace period (Slurm: 30 s), which would
# leave partial output behind; the watchdog removes it first (``on_forced_exit``).
TERM_GRACE_S = 10.0
_FORCED_EXIT_CLEANUPS: list = []
_WATCHDOG: list = []


@contextlib.contextmanager
def on_forced_exit(fn):
    """While the block runs, ``fn()`` is called if a SIGTERM'd tool is ended by the watchdog
    (the only clean-up that then runs: remove a staging folder, say)."""
    _FORCED_EXIT_CLEANUPS.append(fn)
    try:
        yield
    finally:
        _FORCED_EXIT_CLEANUPS.remove(fn)


def _force_exit_after(grace_s: float) -> None:
    import os
    import time

    time.sleep(grace_s)
    for fn in list(_FORCED_EXIT_CLEANUPS):
        try:
            fn()
        except Exception:  # noqa: BLE001 -- exiting anyway; one failed clean-up must not stop the rest
            pass
    sys.stderr.write(f"interrupted; did not unwind within {grace_s:g} s of SIGTERM, partial output removed\n")
    sys.stderr.flush()
    os._exit(INTERRUPTED)


def _terminate_as_interrupt(signum, frame):
    global _TERMINATED
    _TERMINATED = True
    if not _WATCHDOG:
        _WATCHDOG.append(threading.Thread(target=_force_exit_after, args=(TERM_GRACE_S,), daemon=True))
        _WATCHDOG[0].start()
    raise KeyboardInterrupt


def raise_if_terminated() -> None:
    """A safe point: re-raise a SIGTERM whose KeyboardInterrupt was swallowed where it landed
    (a JAX garbage-collection callback, say, which ignores it and carries on)."""
    if _TERMINATED:
        raise KeyboardInterrupt


def _quiet_swallowed_interrupt(previous_hook):
    """An ``sys.unraisablehook`` that drops the "Exception ignored ... Traceback" Python prints for
    a SIGTERM's KeyboardInterrupt swallowed in a callback (``raise_if_terminated`` re-raises it);
    everything else goes to ``previous_hook``."""
    def hook(unraisable):
        if _TERMINATED and unraisable.exc_type is not None and issubclass(unraisable.exc_type, KeyboardInterrupt):
            return
        previous_hook(unraisable)
    return hook


def settings(cls, argv):
    """A benchmark's settings: dataclass ``cls`` from ``key=value`` arguments (``config.load``).

    ``-h`` prints the script's docstring and every setting with its default, then exits 0; a bad key
    or value prints ``error: ...`` (with "did you mean") and exits 2. Errors after this point keep
    their tracebacks (a benchmark's failure is a bug to read, not a user's typo).
    """
    from sim2real.common.config import ConfigError, load

    if any(a in ("-h", "--help", "help") for a in argv):
        from sim2real.common.config import help_text

        print(sys.modules["__main__"].__doc__ or "")
        print(f"settings (key=value):\n{help_text(cls)}")
        sys.exit(0)
    try:
        return load(cls, argv)
    except ConfigError as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(2)


def main_guard(fn, argv, doc: str | None = None, configs: tuple[str, ...] = ()):
    """Run ``fn(argv)``; user errors print ``error: ...`` to stderr and exit with status 2; Ctrl-C
    and SIGTERM exit with status 130 after the job's own clean-up ran. ``-h`` prints ``doc`` (the
    ``__main__`` module's docstring by default) and every key of the ``configs``
    (``"module:Class"`` typed configs: key, type, default, one line of doc), then returns 0."""
    from sim2real._precision import float32
    from sim2real.common.config import ConfigError

    if any(a in ("-h", "--help", "help") for a in argv):
        import importlib

        from sim2real.common.config import help_text

        print(doc if doc is not None else (sys.modules["__main__"].__doc__ or ""))
        for spec in configs:
            module, name = spec.split(":")
            print(f"keys of {name} (key=value):\n{help_text(getattr(importlib.import_module(module), name))}\n")
        return 0
    # SIGTERM (a scheduler's stop) unwinds like Ctrl-C, so every ``finally`` runs
    global _TERMINATED
    _TERMINATED = False
    previous = signal.signal(signal.SIGTERM, _terminate_as_interrupt)
    previous_hook = sys.unraisablehook
    sys.unraisablehook = _quiet_swallowed_interrupt(previous_hook)
    try:
        with float32():  # JAX_ENABLE_X64 in the environment changes nothing (_precision.py)
            fn(argv)
    except (ConfigError, KeyError, ValueError, FileNotFoundError, FileExistsError, TypeError,
            NotADirectoryError, IsADirectoryError, PermissionError) as e:
        msg = e.args[0] if isinstance(e, KeyError) and e.args else str(e)
        print(f"error: {msg}", file=sys.stderr)
        sys.exit(2)
    except Stopped as e:
        print(f"stopped: {e}", file=sys.stderr)
        sys.exit(INTERRUPTED)
    except KeyboardInterrupt:
        print("interrupted; nothing half-written was left behind", file=sys.stderr)
        sys.exit(INTERRUPTED)
    finally:
        signal.signal(signal.SIGTERM, previous)
        sys.unraisablehook = previous_hook
