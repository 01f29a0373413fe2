"""The ``zoetic`` Typer application that every command module registers on (kept apart from
``zoetic.cli``, which imports those modules, so that no module imports its importer)."""

from __future__ import annotations

import typer

app = typer.Typer(
    name="zoetic",
    help="Physics-based artificial animals that learn to move by themselves.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
    context_settings={"help_option_names": ["-h", "--help"]},  # inherited by every command
)

_DEBUG = {"on": False}

# The panels of ``zoetic --help``: what a person comes to do, each command in one.
PANELS = {
    "learn": ("learn", "demo", "repertoire", "abstract", "tasks"),
    "use": ("simulate", "sequence", "track", "macro", "stunt"),
    "look": ("view", "export", "animals"),
    "papers": ("aquarium", "pursue", "san", "reproduce"),
    "bench": ("bench",),
}


def panel_of(name: str) -> tuple[str, int]:
    """Return the --help panel of the top-level command or group ``name`` and its place."""
    place = 0
    for panel, names in PANELS.items():
        if name in names:
            return panel, place + names.index(name)
        place += len(names)
    raise KeyError(f"command {name!r} has no --help panel; add it to zoetic.cli.apps.PANELS")


def assign_panels() -> None:
    """Put every registered top-level command and group into its --help panel, the panels
    and the commands in each in the order of PANELS."""
    for info in (*app.registered_commands, *app.registered_groups):
        info.rich_help_panel = panel_of(_name(info))[0]
    app.registered_commands.sort(key=lambda info: panel_of(_name(info))[1])


def _name(info) -> str:
    """The name a registered command or group is called by."""
    name = info.name or info.callback.__name__
    return name.replace("_", "-")


def _version(value: bool) -> None:
    if value:
        from importlib.metadata import PackageNotFoundError, version

        try:
            number = version("zoetic")
        except PackageNotFoundError:  # run from a source tree that was never installed
            number = "(not installed)"
        print(f"zoetic {number}")
        raise typer.Exit()


@app.callback()
def _root(
    debug: bool = typer.Option(False, "--debug", help="Show full tracebacks."),
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    _DEBUG["on"] = debug
