"""The ``zoetic`` command line: thin wrappers that parse arguments and call the library."""

from __future__ import annotations

import atexit
import gc
import os
import sys

import typer
from rich.markup import escape

from zoetic.cli.apps import _DEBUG, app, assign_panels
from zoetic.cli.output import INTERRUPTED, err_console
from zoetic.errors import ZoeticError

__all__ = ["app", "main"]


def _register() -> None:
    from zoetic.cli import (  # noqa: F401  (commands register)
        aquarium,
        bench,
        blend,
        cluster,
        export,
        learn,
        pursue,
        repertoire,
        reproduce,
        san,
        simulate,
        stunt,
        track,
        view,
    )

    assign_panels()


# the kernel's OpenMP threads sleep at the end of a parallel call instead of spinning for the
# next one (unless the caller's environment says otherwise): a spinning thread takes the core
# that the process's own Python needs between kernel calls (docs/performance.md, "Repertoire
# training in fewer seconds")
OMP_WAIT_POLICY = "PASSIVE"


# the cycle collector's youngest generation is collected after this many allocations in a
# command-line process (Python's default: 700)
COMMAND_GC_THRESHOLD = 7000


def _collect_for_a_command() -> None:
    """Set the cycle collector for a process that is one command: one that allocates mostly
    objects that live as long as it does (modules, numba's types and kernels; some 150 000)
    and then ends. Its young collections run a tenth as often (they would find those objects
    alive), and at exit, after the other handlers (registered later, run earlier), the young
    generations are collected and the objects still alive leave the collector's sight: its
    passes over them at shutdown would free memory the operating system frees at once
    (docs/performance.md, "The third pass: the whole command"). Files are written and closed
    by context managers, so no output waits on a cycle's finalizer at exit."""
    gc.set_threshold(COMMAND_GC_THRESHOLD, *gc.get_threshold()[1:])
    atexit.register(_freeze_at_exit)


def _freeze_at_exit() -> None:
    gc.collect(1)  # the young generations' cycles, finalized before the rest is frozen
    gc.freeze()


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; a ZoeticError prints its message and exits with its code (2; 3 blow-up);
    Ctrl-C exits 130 with one line (a command that can resume says how)."""
    os.environ.setdefault("OMP_WAIT_POLICY", OMP_WAIT_POLICY)  # read when OpenMP first starts
    if argv is None:  # the process's own command line: it ends when the command does
        _collect_for_a_command()
    _register()
    args = sys.argv[1:] if argv is None else argv
    INTERRUPTED["told"] = False
    try:
        code = app(args=args, standalone_mode=False)  # Ctrl-C arrives as the code 130
    except ZoeticError as exc:
        if _DEBUG["on"] or "--debug" in args:
            raise
        # soft wrap: the terminal wraps long lines itself, so paths stay whole (and greppable)
        err_console.print(
            f"[bold red]error:[/] {escape(str(exc))}", highlight=False, soft_wrap=True
        )
        err_console.print("(run with --debug for the traceback)", style="dim", highlight=False)
        return int(getattr(exc, "exit_code", 2))
    except KeyboardInterrupt:
        code = 130
    except typer.Exit as exc:
        return exc.exit_code
    except SystemExit as exc:  # click usage errors arrive this way in non-standalone mode
        return int(exc.code or 0)
    except typer.Abort:
        err_console.print("[yellow]aborted[/]")
        return 130
    except Exception as exc:  # usage errors (click's, or the copy vendored in newer Typer)
        shows = callable(getattr(exc, "show", None))
        if shows and isinstance(getattr(exc, "exit_code", None), int):
            exc.show()
            return 2
        if _DEBUG["on"] or "--debug" in args:
            raise
        err_console.print(
            f"[bold red]internal error:[/] {type(exc).__name__}: {escape(str(exc)[:300])}; "
            "this is a bug in zoetic: run again with --debug for the traceback and report it",
            highlight=False,
            soft_wrap=True,
        )
        return 1
    code = code if isinstance(code, int) else 0
    if code == 130 and not INTERRUPTED["told"]:
        err_console.print("[yellow]interrupted (Ctrl-C); the command stopped[/]", highlight=False)
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
