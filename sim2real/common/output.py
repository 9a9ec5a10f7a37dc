"""Output folders the tools create, and the only rule by which anything is ever removed.

A folder is created with a marker file (``.sim2real``, naming the tool that made it). An existing
folder is replaced or removed only when it carries the marker of the same tool; a folder without
it -- one the user made, ``.``, a folder holding any of the inputs or one of their parents -- is
refused with a message, whatever ``overwrite`` says. Results that are built in one go (a
diagnosis, an evaluation) are written into a hidden sibling folder first and moved into place only
when complete, so a failure, Ctrl-C or SIGTERM leaves neither a half-written result nor the
temporary folder.

    with staged("diag", kind="diagnosis", inputs=["robot.xml", "run1.csv"], overwrite=True) as tmp:
        write_everything_into(tmp)          # moved to diag/ only if this block finishes
"""
from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
import time

from sim2real.common.cli import on_forced_exit, raise_if_terminated

MARKER = ".sim2real"


class OutputError(ValueError):
    """An output folder that may not be written, replaced or removed; the message says why."""


def marker_kind(path: str) -> str | None:
    """The tool that made ``path`` (``diagnosis``, ``run``, ...), or None if it has no marker."""
    try:
        with open(os.path.join(path, MARKER)) as f:
            return json.load(f).get("kind")
    except (OSError, ValueError, AttributeError):
        return None


def write_marker(path: str, kind: str) -> None:
    with open(os.path.join(path, MARKER), "w") as f:
        json.dump({"kind": kind, "created": time.strftime("%Y-%m-%d %H:%M:%S")}, f)


def _inside(child: str, parent: str) -> bool:
    return child == parent or child.startswith(parent.rstrip(os.sep) + os.sep)


def check(path: str, kind: str, inputs=(), overwrite: bool = False, keep_existing: bool = False,
          key: str = "out") -> str:
    """Refuse an output folder that must not be used; returns its absolute path.

    Args:
      path: the folder asked for (``key=path`` on the command line; ``key`` names it in messages).
      kind: the tool's marker name.
      inputs: files the tool reads; the folder may not hold any of them.
      overwrite: an existing non-empty folder may be replaced (only if it has ``kind``'s marker).
      keep_existing: the folder is continued, not replaced (resume); it must be this tool's.
    """
    if not path:
        raise OutputError(f"{key}= is empty; name an output folder")
    p = os.path.realpath(path)
    protected = {os.path.realpath(os.getcwd()), os.path.realpath(os.path.expanduser("~")), os.path.realpath(os.sep)}
    if p in protected:
        raise OutputError(f"{key}={path} is the current, home or root folder; name a new folder for the output")
    for inp in inputs:
        if inp and _inside(os.path.realpath(inp), p):
            raise OutputError(f"{key}={path} holds the input '{inp}'; write the output to another folder")
    if os.path.exists(p) and not os.path.isdir(p):
        raise OutputError(f"{key}={path} is an existing file, not a folder")
    if os.path.isdir(p) and os.listdir(p):
        owner = marker_kind(p)
        if keep_existing:
            if owner not in (kind, None):
                raise OutputError(f"{key}={path} was made by sim2real's {owner}, not by {kind}")
        elif not overwrite:
            raise FileExistsError(f"{key}={path} exists; pass overwrite=true to replace it, or another {key}=")
        elif owner != kind:
            made = f"by sim2real's {owner}" if owner else "by sim2real (it has no .sim2real marker)"
            raise OutputError(f"{key}={path} was not made {made}: it is never replaced, whatever overwrite says; "
                              f"choose another {key}=")
    parent = os.path.dirname(p)
    probe = parent
    while not os.path.exists(probe):
        probe = os.path.dirname(probe)
    if not os.path.isdir(probe) or not os.access(probe, os.W_OK | os.X_OK):
        raise OutputError(f"{key}={path}: cannot create a folder in '{probe}' (not a writable folder)")
    return p


def create(path: str, kind: str, inputs=(), overwrite: bool = False, key: str = "out") -> str:
    """Create (or, with ``overwrite`` and this tool's marker, empty and re-create) a folder that is
    filled in place (a training run). Returns its absolute path."""
    p = check(path, kind, inputs, overwrite, key=key)
    if os.path.isdir(p) and os.listdir(p):
        remove(p, kind)
    os.makedirs(p, exist_ok=True)
    write_marker(p, kind)
    return p


def remove(path: str, kind: str) -> None:
    """Delete a folder this tool made (refused without its marker)."""
    if marker_kind(path) != kind:
        raise OutputError(f"'{path}' has no sim2real {kind} marker; it is not removed")
    shutil.rmtree(path)


@contextlib.contextmanager
def staged(path: str, kind: str, inputs=(), overwrite: bool = False, key: str = "out"):
    """Build a result in a hidden sibling folder; it replaces ``path`` only when the block ends
    without an exception. Yields the temporary folder."""
    p = check(path, kind, inputs, overwrite, key=key)
    parent = os.path.dirname(p)
    made = []  # parent folders this call creates (removed again if the result never arrives)
    probe = parent
    while not os.path.exists(probe):
        made.append(probe)
        probe = os.path.dirname(probe)
    try:
        os.makedirs(parent, exist_ok=True)
    except OSError as e:
        raise OutputError(f"{key}={path}: cannot create its parent folder ({e.strerror})") from None
    tmp = tempfile.mkdtemp(prefix=f".{os.path.basename(p)}.partial-", dir=parent)

    def discard():
        shutil.rmtree(tmp, ignore_errors=True)
        for folder in made:  # deepest first
            try:
                os.rmdir(folder)
            except OSError:
                break

    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o777 & ~umask)  # mkdtemp makes it private; the result is an ordinary folder
        write_marker(tmp, kind)
        with on_forced_exit(discard):
            yield tmp
        raise_if_terminated()  # a SIGTERM swallowed during the block: the result never replaces path
        old = None
        if os.path.isdir(p) and os.listdir(p):
            check(path, kind, inputs, overwrite, key=key)  # still ours (nothing changed meanwhile)
            old = tempfile.mkdtemp(prefix=f".{os.path.basename(p)}.old-", dir=parent)
            os.replace(p, os.path.join(old, "x"))
        elif os.path.isdir(p):
            os.rmdir(p)  # an empty folder the user made for us: nothing to lose
        try:
            os.replace(tmp, p)
        except OSError:
            if old is not None:  # put the previous result back
                os.replace(os.path.join(old, "x"), p)
                os.rmdir(old)
            raise
        if old is not None:
            shutil.rmtree(old)
    except BaseException:
        discard()
        raise
