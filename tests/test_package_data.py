"""Every data file under src/zoetic ships in the wheel: it matches a package-data pattern."""

from __future__ import annotations

import tomllib
from fnmatch import fnmatch
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "zoetic"


def _patterns() -> list[str]:
    doc = tomllib.loads((ROOT / "pyproject.toml").read_text())
    return doc["tool"]["setuptools"]["package-data"]["zoetic"]


def _data_files() -> list[str]:
    return sorted(
        p.relative_to(PACKAGE).as_posix()
        for p in PACKAGE.rglob("*")
        if p.is_file() and p.suffix not in (".py", ".pyc") and "__pycache__" not in p.parts
    )


def test_data_files_exist() -> None:
    names = _data_files()
    assert any(n.startswith("tasks/tricks/") for n in names)
    assert any(n.startswith("behavior/aquarium/skills/") for n in names)


def test_every_data_file_is_package_data() -> None:
    patterns = _patterns()

    # fnmatch's * crosses "/", so compare segment counts too: "tasks/*.toml" is not tricks/
    def shipped(name: str) -> bool:
        return any(fnmatch(name, p) and name.count("/") == p.count("/") for p in patterns)

    missing = [n for n in _data_files() if not shipped(n)]
    assert not missing, f"not in [tool.setuptools.package-data] of pyproject.toml: {missing}"
