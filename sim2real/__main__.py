"""``python -m sim2real <command> key=value ...``: the same commands as ``sim2real-<command>``."""
import importlib
import sys

from sim2real.commands import COMMANDS


def main(argv: list[str]) -> int:
    if not argv or argv[0] not in COMMANDS:
        print(f"usage: python -m sim2real {{{','.join(COMMANDS)}}} key=value ...  (-h after a command lists its keys)",
              file=sys.stderr if argv else sys.stdout)
        return 2 if argv else 0
    importlib.import_module(f"sim2real.commands.{argv[0]}").run(argv[1:])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
