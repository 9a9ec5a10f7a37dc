"""Shared command-line plumbing: clean one-line errors and non-zero exit codes."""
from __future__ import annotations

import sys


def main_guard(fn, argv):
    """Run ``fn(argv)``; user errors print ``error: ...`` to stderr and exit with status 2."""
    from sim2real.config import ConfigError

    if any(a in ("-h", "--help", "help") for a in argv):
        print(sys.modules["__main__"].__doc__ or "")
        return 0
    try:
        fn(argv)
    except (ConfigError, KeyError, ValueError, FileNotFoundError, FileExistsError, TypeError) as e:
        msg = e.args[0] if isinstance(e, KeyError) and e.args else str(e)
        print(f"error: {msg}", file=sys.stderr)
        sys.exit(2)
