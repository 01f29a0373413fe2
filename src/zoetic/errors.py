"""One exception family for everything a user can get wrong or a run can hit."""


class ZoeticError(Exception):
    """Base of all zoetic errors; the CLI prints the message and exits with code 2."""


class BodyError(ZoeticError):
    """An animal or creature file is malformed or physically invalid."""


class ControllerError(ZoeticError):
    """A controller file is malformed or does not fit the animal."""


class SimulationError(ZoeticError):
    """A simulation blew up or was given inconsistent inputs."""


class TaskError(ZoeticError):
    """A task file is malformed."""


class RunDirError(ZoeticError):
    """A run directory is missing, incomplete or inconsistent."""
