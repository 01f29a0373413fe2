"""Numba's kernel cache kept fresh across modules (``zoetic.jitcache``): the covered modules
match the source tree, an edit to an inlined helper's module reaches the next process, and a
cache that cannot be written is harmless."""

from __future__ import annotations

import ast
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from zoetic import jitcache
from zoetic.jitcache import IMPORTED, KERNELS, PACKAGE, SOURCES, refresh, source_digest

SRC = PACKAGE.parent


def _top_level_imports(tree: ast.Module):
    """Yield the module-level import statements of a file (those in a top-level try too)."""
    for node in tree.body:
        inner = (
            node.body + [n for h in node.handlers for n in h.body]
            if isinstance(node, ast.Try)
            else [node]
        )
        yield from (n for n in inner if isinstance(n, ast.Import | ast.ImportFrom))


def _imported_modules(node: ast.Import | ast.ImportFrom) -> list[str]:
    """Return the absolute module names an import statement names."""
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names]
    return [node.module or ""]


def _file_of(module: str) -> str | None:
    """Return the package-relative file of a zoetic module, or None if it is not one."""
    if not module.startswith("zoetic."):
        return None
    rel = Path(*module.split(".")[1:])
    if (PACKAGE / rel).is_dir():
        return (rel / "__init__.py").as_posix()
    return rel.with_suffix(".py").as_posix()


def _scan() -> tuple[set[str], set[str]]:
    """Return (modules that import Numba at module level, zoetic modules those import)."""
    kernels, imported = set(), set()
    trees = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text())
        names = [m for n in _top_level_imports(tree) for m in _imported_modules(n)]
        if any(m == "numba" or m.startswith("numba.") for m in names):
            rel = path.relative_to(PACKAGE).as_posix()
            kernels.add(rel)
            trees[rel] = names
    for names in trees.values():
        imported |= {f for m in names if (f := _file_of(m)) is not None}
    return kernels, imported - kernels - {"jitcache.py"}


def test_the_covered_modules_are_those_that_define_compiled_code_and_what_they_import():
    kernels, imported = _scan()
    assert set(KERNELS) == kernels
    assert set(IMPORTED) == imported


def test_every_kernel_module_checks_the_cache_before_it_defines_a_kernel():
    for rel in KERNELS:
        body = ast.parse((PACKAGE / rel).read_text()).body
        calls = [
            i
            for i, node in enumerate(body)
            if isinstance(node, ast.Expr) and ast.unparse(node) == "fresh_numba_cache()"
        ]
        defs = [
            i for i, node in enumerate(body) if isinstance(node, ast.FunctionDef | ast.ClassDef)
        ]
        assert calls and calls[0] < min(defs, default=len(body)), rel


def test_the_digest_changes_when_any_covered_file_changes(tmp_path):
    paths = []
    for rel in SOURCES:
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        paths.append(Path(shutil.copy(PACKAGE / rel, tmp_path / rel)))
    before = source_digest(paths)
    assert before == source_digest(list(reversed(paths)))  # the order given does not matter
    for path in paths:
        text = path.read_bytes()
        path.write_bytes(text.replace(b"\n", b"\n ", 1))  # one more byte: a new digest
        assert source_digest(paths) != before, path
        path.write_bytes(text)
    assert source_digest(paths) == before


def test_the_kernel_cache_directory_is_where_numba_caches():
    from zoetic.physics import broadphase

    assert Path(broadphase.near._cache.cache_path) == jitcache.numba_cache_dir(
        Path(broadphase.__file__).parent
    )


def test_a_missing_source_or_an_unwritable_cache_is_harmless(tmp_path, monkeypatch):
    from numba.core import config

    source = tmp_path / "kernels.py"
    source.write_text("x = 1\n")
    assert refresh([tmp_path / "gone.py"], [source]) == []
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setattr(config, "CACHE_DIR", str(blocker / "cache"))  # under a file: unwritable
    assert jitcache.numba_cache_dir(tmp_path) is None
    assert refresh([source], [source]) == []
    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path / "cache"))
    cleared = refresh([source], [source])  # first look: no stamp, so whatever is there goes
    assert len(cleared) == 1 and (cleared[0] / jitcache.STAMP).is_file()
    assert refresh([source], [source]) == []  # stamped: nothing to do


def test_processes_starting_at_once_leave_one_whole_stamp(tmp_path, monkeypatch):
    from concurrent.futures import ThreadPoolExecutor

    from numba.core import config

    source = tmp_path / "kernels.py"
    source.write_text("x = 1\n")
    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path / "cache"))
    cache = jitcache.numba_cache_dir(tmp_path)
    for n in range(20):  # stale machine code of the kernel module, and another module's
        (cache / f"kernels.f-{n}.py311.nbi").write_text("")
        (cache / f"other.f-{n}.py311.nbi").write_text("")
    with ThreadPoolExecutor(8) as pool:
        cleared = list(pool.map(lambda _: refresh([source], [source]), range(16)))
    assert any(cleared)
    assert (cache / jitcache.STAMP).read_text() == source_digest([source])
    left = sorted(p.name for p in cache.iterdir())
    assert left == sorted([jitcache.STAMP] + [f"other.f-{n}.py311.nbi" for n in range(20)])


MAIN = """\
import sys
from pathlib import Path

from numba import njit

HERE = Path(__file__).parent
if sys.argv[1] == "guard":
    from zoetic.jitcache import refresh

    refresh([HERE / "main.py", HERE / "helper.py"], [HERE / "main.py", HERE / "helper.py"])

from helper import shift


@njit(cache=True)
def shifted(x):
    return shift(x)


print(shifted(1.0))
"""
HELPER = """\
from numba import njit


@njit(inline="always")
def shift(x):
    return x + {}
"""


def _run(folder: Path, mode: str) -> float:
    """Run the two-module program in ``folder`` in a new process and return what it printed."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(folder / "cache"), "PYTHONPATH": str(SRC)}
    out = subprocess.run(
        [sys.executable, str(folder / "main.py"), mode],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return float(out.stdout.split()[-1])


@pytest.mark.parametrize("mode", ["guard", "numba-alone"])
def test_an_edit_to_an_inlined_helpers_module_reaches_the_next_process(tmp_path, mode):
    (tmp_path / "main.py").write_text(MAIN)
    (tmp_path / "helper.py").write_text(HELPER.format("1.0"))
    assert _run(tmp_path, mode) == 2.0
    (tmp_path / "helper.py").write_text(HELPER.format("5.0"))  # main.py itself unchanged
    cached = list((tmp_path / "cache").rglob("main.shifted-*.nbc"))
    assert cached  # the first run's machine code is on disk
    if mode == "guard":
        assert _run(tmp_path, mode) == 6.0
    else:  # Numba on its own serves the stale machine code: the trap the guard closes
        assert _run(tmp_path, mode) == 2.0
