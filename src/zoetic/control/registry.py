"""Controller kinds added by later layers (abstracted, sequences) register their loaders here."""

from __future__ import annotations

from collections.abc import Callable

from zoetic.errors import ControllerError

_LOADERS: dict[str, Callable[[dict], object]] = {}


def register_kind(kind: str, loader: Callable[[dict], object]) -> None:
    """Make ``control.from_dict`` understand controllers of type ``kind``."""
    _LOADERS[kind] = loader


def from_dict_extra(d: dict, where: str):
    """Return a controller of a registered extra kind; ControllerError for an unknown type."""
    loader = _LOADERS.get(d.get("type"))
    if loader is None:
        raise ControllerError(f"unknown controller type {d.get('type')!r}")
    return loader(d)
