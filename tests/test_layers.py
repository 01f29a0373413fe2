"""Layers that hold: every import in src/zoetic goes down the DESIGN.md list, and matplotlib is
imported only in viz/. Function-level (lazy) imports count as much as module-level ones."""

from __future__ import annotations

import ast
from pathlib import Path

import zoetic

ROOT = Path(zoetic.__file__).parent

# DESIGN.md, "Layers": a module imports only from its own layer or those before it.
LAYERS = {
    "errors": 0, "io": 0, "record": 0,
    "bodies": 1,
    "physics": 2,
    "render": 3,
    "control": 4,
    "tasks": 5,
    "learn": 6, "runs": 6,  # run directories: configs, checks, the record; no pictures
    "perception": 7, "behavior": 7,
    "viz": 8, "web": 8, "gym": 8, "cli": 8, "bench": 8,
}  # fmt: skip
TOP = 8
SAN = "san"  # its own slice: may import anything below behavior, and viz; only the top imports it
SAN_MAY_IMPORT = {name for name, level in LAYERS.items() if level < LAYERS["behavior"]} | {"viz"}
TOP_FILES = {"__init__", "__main__"}  # the package's face and the entry point


def _unit(path: Path, root: Path) -> str:
    """Return the layer unit a source file belongs to (its sub-package or top-level module)."""
    rel = path.relative_to(root)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def _level(unit: str, path: Path | None = None) -> int:
    if unit in TOP_FILES:
        return TOP
    return LAYERS[unit]


def _imports(tree: ast.AST, path: Path, root: Path):
    """Yield (line, module) for every import in a file, relative ones resolved."""
    package = ".".join(("zoetic", *path.relative_to(root).with_suffix("").parts[:-1]))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            yield node.lineno, mod
            if mod == "zoetic":  # from zoetic import physics
                for alias in node.names:
                    yield node.lineno, f"zoetic.{alias.name}"


def violations(root: Path = ROOT) -> list[str]:
    """Return one line per import that goes up a layer, or matplotlib outside viz/."""
    out = []
    for path in sorted(root.rglob("*.py")):
        unit = _unit(path, root)
        rel = path.relative_to(root.parent)
        tree = ast.parse(path.read_text(), str(path))
        for line, mod in _imports(tree, path, root):
            top = mod.split(".")[0]
            if top == "matplotlib" and unit != "viz":
                out.append(f"{rel}:{line}: imports matplotlib outside viz/")
            if top != "zoetic" or mod == "zoetic":
                continue
            parts = mod.split(".")
            target = parts[1]
            if target == unit:
                continue
            if target in TOP_FILES and _level(unit, path) < TOP:
                out.append(f"{rel}:{line}: {unit} imports {mod} (the top level)")
                continue
            if target not in LAYERS and target != SAN and target not in TOP_FILES:
                out.append(f"{rel}:{line}: imports {mod}, which is in no layer")
                continue
            if unit == SAN:
                if target not in SAN_MAY_IMPORT:
                    out.append(f"{rel}:{line}: san imports {mod} (only below behavior, and viz)")
                continue
            if target == SAN:
                if _level(unit, path) < TOP:
                    out.append(f"{rel}:{line}: {unit} imports {mod} (only the top imports san)")
                continue
            if target in TOP_FILES:
                continue
            if LAYERS[target] > _level(unit, path):
                out.append(f"{rel}:{line}: {unit} (layer {_level(unit, path)}) imports {mod} "
                           f"(layer {LAYERS[target]})")  # fmt: skip
    return out


def test_imports_only_go_down_the_layers():
    assert violations() == []


def test_the_checker_catches_upward_imports_and_stray_matplotlib(tmp_path):
    pkg = tmp_path / "zoetic"
    for name, text in {
        "physics/step.py": "from zoetic.control import Controller\n",
        "control/lazy.py": "def f():\n    from zoetic.learn.run import Run\n",
        "tasks/plot.py": "import matplotlib.pyplot as plt\n",
        "learn/ok.py": "from zoetic.physics import simulate\nfrom . import run\n",
        "learn/rel.py": "from ..behavior import macro\n",
        "behavior/ok.py": "from zoetic.learn.optimizers import Annealing\n",
        "san/bad.py": "from zoetic.behavior.macro import search\n",
        "physics/bench.py": "from zoetic.control import wave_controller\n",
        "learn/timing.py": "def f():\n    from zoetic.bench.simulate import bench_simulate\n",
        "bench/fine.py": "from zoetic.behavior.skills import skill_figures\n",
        "viz/fine.py": "import matplotlib\n",
        "cli/fine.py": "from zoetic.runs import finish_run\nfrom zoetic.san import tune\n",
        "behavior/up.py": "from zoetic.__main__ import main\nfrom zoetic.san import tune\n",
        "physics/runs.py": "from zoetic.runs import finish_run\n",
    }.items():
        (pkg / name).parent.mkdir(parents=True, exist_ok=True)
        (pkg / name).write_text(text)
    found = "\n".join(violations(pkg))
    assert "step.py:1: physics (layer 2) imports zoetic.control" in found
    assert "lazy.py:2: control (layer 4) imports zoetic.learn.run" in found
    assert "plot.py:1: imports matplotlib outside viz/" in found
    assert "rel.py:1: learn (layer 6) imports zoetic.behavior" in found
    assert "bad.py:1: san imports zoetic.behavior.macro" in found
    assert "up.py:1: behavior imports zoetic.__main__ (the top level)" in found
    assert "runs.py:1: physics (layer 2) imports zoetic.runs (layer 6)" in found
    assert "up.py:2: behavior imports zoetic.san (only the top imports san)" in found
    # benchmarks live in zoetic.bench, the top layer: a driver left below is checked as such
    assert "bench.py:1: physics (layer 2) imports zoetic.control" in found
    assert "timing.py:2: learn (layer 6) imports zoetic.bench.simulate (layer 8)" in found
    assert "ok.py" not in found and "fine.py" not in found
