"""What an animal IS: animal files, their validation, and the compiled Body arrays."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from zoetic.bodies.body import Body, compile_body
from zoetic.bodies.spec import AnimalSpec, parse_animal, read_animal_file
from zoetic.errors import BodyError
from zoetic.io import is_path, suggest

ZOO_DIR = Path(__file__).parent / "zoo"

__all__ = [
    "ZOO_DIR",
    "AnimalSpec",
    "Body",
    "compile_body",
    "list_animals",
    "load_animal",
    "parse_animal",
    "read_animal_file",
]


def list_animals() -> list[str]:
    """Return the names of the built-in animals, in zoo order."""
    order = ["snake", "shark", "ray", "dolphin"]
    names = sorted(p.stem for p in ZOO_DIR.glob("*.toml"))
    return [n for n in order if n in names] + [n for n in names if n not in order]


@lru_cache(maxsize=32)
def _compiled(path: str, text: bytes) -> Body:
    """Return the Body of an animal file with this text (keyed by content: an edited file is
    compiled afresh, an unchanged one is the same object)."""
    return compile_body(read_animal_file(path))


def _load_path(path: str) -> Body:
    try:
        text = Path(path).read_bytes()
    except OSError as exc:
        raise BodyError(f"{path}: cannot read ({exc.strerror or exc})") from None
    return _compiled(path, text)


def load_animal(name_or_path: str | Path) -> Body:
    """Return the compiled Body of a zoo animal's name or of an animal TOML file's path.

    A bare name (``shark``) always means the zoo entry; a file is written as a path
    (``./shark.toml``, ``animals/shark.toml``), so a folder named ``shark`` cannot hide it.
    """
    text = str(name_or_path)
    if is_path(text):
        candidate = Path(text)
        if candidate.is_dir():
            raise BodyError(f"{text}: is a directory, not an animal file")
        if not candidate.is_file():
            raise BodyError(f"{text}: no such animal file")
        return _load_path(str(candidate.resolve()))
    zoo_file = ZOO_DIR / f"{text}.toml"
    if not zoo_file.is_file():
        hint = f" (to use the file {text!r} here, write ./{text})" if Path(text).exists() else ""
        raise BodyError(
            f"unknown animal {text!r}{suggest(text, list_animals())}: choose one of "
            f"{', '.join(list_animals())} or give the path of an animal .toml file{hint}"
        )
    return _load_path(str(zoo_file))
