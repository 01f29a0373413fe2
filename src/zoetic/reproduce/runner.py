"""Run one experiment script or zoetic command with the provenance hook installed.

``python -m zoetic.reproduce.runner LOG script.py ARGS...`` or
``python -m zoetic.reproduce.runner LOG -m zoetic ARGS...``: every package data file the run
opens is noted in LOG (:mod:`zoetic.reproduce.provenance`), then the script or module runs as
``__main__`` with ARGS as its command line.
"""

from __future__ import annotations

import runpy
import sys

from zoetic.reproduce.provenance import install


def main(argv: list[str]) -> None:
    """Install the hook on ``argv[0]`` (the log) and run the rest as a command line."""
    if len(argv) < 2 or (argv[1] == "-m" and len(argv) < 3):
        sys.exit("usage: python -m zoetic.reproduce.runner LOG (script.py | -m module) [ARGS]")
    install(argv[0])
    if argv[1] == "-m":
        sys.argv = [argv[2], *argv[3:]]
        runpy.run_module(argv[2], run_name="__main__", alter_sys=True)
    else:
        sys.argv = argv[1:]
        runpy.run_path(argv[1], run_name="__main__")


if __name__ == "__main__":
    main(sys.argv[1:])
