"""A figure drawn by a second process, on the other core: it starts when a command does,
imports matplotlib while the command imports and works on,
then draws the one figure asked of it and writes it, while the command goes on to what
follows the figure.

The command asks with the drawing function's name (one of ``DRAWN``) and its arguments
(pickled over the process's standard input); the process answers with the path written.
Should it fail to answer (it could not start, it died, the drawing raised), the figure is
drawn in the command's own process, by the same function, so the file is the same either way
and a drawing's error is raised where the command can report it.
"""

from __future__ import annotations

import os
import pickle
import select
import signal
import subprocess
import sys
from pathlib import Path

# s: a second process that has not answered by then is ended, and the figure drawn here
ANSWER_WITHIN = 120.0

# the functions a Drawer draws with, by name: module and attribute within zoetic.viz
DRAWN = {"plot_repertoire": ("zoetic.viz.abstraction", "plot_repertoire")}


def _function(name: str):
    import importlib

    module, attribute = DRAWN[name]
    return getattr(importlib.import_module(module), attribute)


class Drawer:
    """The second process (``with Drawer() as d: ...; d.draw(name, *args); ...; d.wait()``)."""

    def __init__(self) -> None:
        # the directory that holds this zoetic, after the process's own path (so that it
        # finds this package, as imported here, without shadowing anything before it)
        package_root = str(Path(__file__).resolve().parents[2])
        path = [*filter(None, [os.environ.get("PYTHONPATH")]), package_root]
        # one BLAS thread: the command's own threads have the cores while it draws
        env = os.environ | {"PYTHONPATH": os.pathsep.join(path), "OPENBLAS_NUM_THREADS": "1"}
        self._asked: tuple | None = None
        try:
            self._proc: subprocess.Popen | None = subprocess.Popen(
                [sys.executable, "-P", "-m", "zoetic.viz.drawer"],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=subprocess.DEVNULL,
                env=env,
            )
        except OSError:
            self._proc = None  # drawn here instead (wait)

    def draw(self, name: str, *args, **kwargs) -> None:
        """Ask for the figure ``DRAWN[name](*args, **kwargs)``; ``wait`` returns its path."""
        self._asked = (name, args, kwargs)
        if self._proc is None:
            return
        try:
            pickle.dump(self._asked, self._proc.stdin)
            self._proc.stdin.close()
        except OSError:  # the process has gone: drawn here instead
            self.close()

    def wait(self) -> Path:
        """Return the path of the figure asked for, once written (by the second process, or
        drawn here if it did not answer)."""
        if self._asked is None:
            raise RuntimeError("Drawer.wait: no figure was asked for")
        answer = None
        if self._proc is not None:
            ready, _, _ = select.select([self._proc.stdout], [], [], ANSWER_WITHIN)
            try:
                answer = pickle.load(self._proc.stdout) if ready else None
            except Exception:  # noqa: BLE001  (no answer we can read: drawn here instead)
                answer = None
            self.close()
        if isinstance(answer, Path):
            return answer
        name, args, kwargs = self._asked
        return _function(name)(*args, **kwargs)

    def close(self) -> None:
        """End the second process: it has answered, or is not needed any more."""
        proc, self._proc = self._proc, None
        if proc is None:
            return
        for stream in (proc.stdin, proc.stdout):
            try:
                stream.close()
            except OSError:
                pass
        proc.kill()  # an answered figure is written already
        proc.wait()

    def __enter__(self) -> Drawer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _serve() -> None:
    """The second process: import matplotlib, read one request, draw it, answer the path."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the command's: it closes our input
    answers = os.fdopen(os.dup(1), "wb")  # the answer's own stream: what a library prints
    os.dup2(2, 1)  # goes where the errors go, not into the answer
    from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: F401
    from matplotlib.figure import Figure  # noqa: F401

    for name in DRAWN:
        _function(name)
    try:
        name, args, kwargs = pickle.load(sys.stdin.buffer)
    except (EOFError, OSError):
        os._exit(0)  # nothing asked
    try:
        answer = _function(name)(*args, **kwargs)
    except Exception:  # noqa: BLE001  (drawn again by the command, which reports the error)
        answer = None
    pickle.dump(answer, answers)
    answers.flush()
    os._exit(0)  # no shutdown passes over matplotlib's objects: the answer is given


if __name__ == "__main__":
    _serve()
