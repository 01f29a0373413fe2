"""One exception family for everything a user can get wrong or a run can hit."""


class ZoeticError(Exception):
    """Base of all zoetic errors; the CLI prints the message and exits with ``exit_code``."""

    exit_code = 2


class BodyError(ZoeticError):
    """An animal or creature file is malformed or physically invalid."""


class ControllerError(ZoeticError):
    """A controller file is malformed or does not fit the animal."""


class SimulationError(ZoeticError):
    """A simulation was given inconsistent inputs (a time step too large for the body, ...)."""


class BlowUpError(SimulationError):
    """A simulation blew up (non-finite or runaway state) although its inputs were accepted."""

    exit_code = 3


class TaskError(ZoeticError):
    """A task file is malformed."""


class RunDirError(ZoeticError):
    """A run directory is missing, incomplete or inconsistent."""


def naming(source: object, exc: ZoeticError) -> ZoeticError:
    """Return ``exc`` with its message prefixed by ``source`` (a file or directory) if needed."""
    text, src = str(exc), str(source)
    if text.startswith(src) or f"{src}/" in text or f"{src}:" in text or f" {src} " in text:
        return exc
    new = type(exc)(f"{source}: {text}")
    return new
