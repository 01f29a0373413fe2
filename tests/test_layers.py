"""Layers that hold: every import in src/zoetic goes down the DESIGN.md list, with no exceptions;
no modules import each other in a cycle; matplotlib is imported only in viz/. Function-level
(lazy) imports count as much as module-level ones."""

from __future__ import annotations

import ast
from pathlib import Path

import zoetic

ROOT = Path(zoetic.__file__).parent

# DESIGN.md, "Layers": a module imports only from its own layer or those before it. The top of
# the list is split so that nothing in the library draws: viz draws from results and run
# files, called from the command line (and the benchmarks); runs, gym and web do not import it.
LAYERS = {
    "errors": 0,
    "io": 0,
    "outdir": 0,  # run directories and the --out convention
    "record": 0,  # the run record: one writer, one reader (NumPy and JSON)
    "jitcache": 0,  # Numba's kernel cache kept fresh across modules
    "bodies": 1,
    "physics": 2,
    "render": 3,
    "control": 4,
    "tasks": 5,
    "learning": 6,
    "perception": 7,
    "behavior": 7,
    "runs": 8,
    "gym": 8,
    "web": 8,
    "viz": 9,
    "cli": 10,
    "bench": 10,
    "reproduce": 10,  # zoetic reproduce: runs experiments, may import anything
    "__init__": 10,  # the package's face
    "__main__": 10,  # the entry point
}
SAN = "san"  # its own slice: imports only what lies below behavior; viz draws its pictures
SAN_MAY_IMPORT = {name for name, level in LAYERS.items() if level < LAYERS["behavior"]}
SAN_IMPORTED_FROM = LAYERS["viz"]  # viz (its pictures) and above import san


def _unit(path: Path, root: Path) -> str:
    """Return the layer unit a source file belongs to (its sub-package or top-level module)."""
    rel = path.relative_to(root)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def _module(path: Path, root: Path) -> str:
    """Return the dotted module name of a source file (a package's __init__ is the package)."""
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _type_checking_lines(tree: ast.AST) -> set[int]:
    """Return the lines of imports that only type checkers see (``if TYPE_CHECKING:``)."""
    lines = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in node.body:
                for inner in ast.walk(sub):
                    if isinstance(inner, ast.Import | ast.ImportFrom):
                        lines.add(inner.lineno)
    return lines


def _imports(tree: ast.AST, path: Path, root: Path):
    """Yield (line, module) for every import in a file, relative ones resolved; ``from a
    import b`` yields a and a.b (b may be a module)."""
    package = ".".join(("zoetic", *path.relative_to(root).with_suffix("").parts[:-1]))
    if path.name == "__init__.py":
        package = _module(path, root)
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
            for alias in node.names:
                if mod.startswith("zoetic") and alias.name != "*":
                    yield node.lineno, f"{mod}.{alias.name}"


def _sources(root: Path):
    for path in sorted(root.rglob("*.py")):
        yield path, ast.parse(path.read_text(), str(path))


def violations(root: Path = ROOT) -> list[str]:
    """Return one line per import that goes up a layer, or matplotlib outside viz/."""
    out = []
    for path, tree in _sources(root):
        unit = _unit(path, root)
        rel = path.relative_to(root.parent)
        seen = set()
        for line, mod in _imports(tree, path, root):
            parts = mod.split(".")
            if parts[0] == "matplotlib" and unit != "viz":
                out.append(f"{rel}:{line}: imports matplotlib outside viz/")
            if parts[0] != "zoetic" or len(parts) < 2 or (line, parts[1]) in seen:
                continue
            target = parts[1]
            seen.add((line, target))
            if target == unit:
                continue
            if target not in LAYERS and target != SAN:
                out.append(f"{rel}:{line}: imports {mod}, which is in no layer")
            elif unit == SAN:
                if target not in SAN_MAY_IMPORT:
                    out.append(f"{rel}:{line}: san imports {mod} (only what lies below behavior)")
            elif target == SAN:
                if LAYERS[unit] < SAN_IMPORTED_FROM:
                    why = "only viz and above import san"
                    out.append(f"{rel}:{line}: {unit} imports {mod} ({why})")
            elif LAYERS[target] > LAYERS[unit]:
                out.append(
                    f"{rel}:{line}: {unit} (layer {LAYERS[unit]}) imports {mod} "
                    f"(layer {LAYERS[target]})"
                )
    return out


def _targets(tree: ast.AST, path: Path, root: Path):
    """Yield (line, module, name or None) for every imported module and imported name."""
    package = (
        _module(path, root)
        if path.name == "__init__.py"
        else ".".join(("zoetic", *path.relative_to(root).with_suffix("").parts[:-1]))
    )
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name, None
        elif isinstance(node, ast.ImportFrom):
            mod = node.module or ""
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            for alias in node.names:
                yield node.lineno, mod, alias.name


def import_graph(root: Path = ROOT) -> dict[str, dict[str, int]]:
    """Return {module: {module it imports: line}} over the package's modules, function-level
    imports included, type-checking-only ones left out."""
    paths = {_module(p, root): p for p in sorted(root.rglob("*.py"))}
    graph: dict[str, dict[str, int]] = {m: {} for m in paths}
    for mod, path in paths.items():
        tree = ast.parse(path.read_text(), str(path))
        skip = _type_checking_lines(tree)
        for line, target, alias in _targets(tree, path, root):
            if line in skip:
                continue
            if alias is not None and f"{target}.{alias}" in paths:
                target = f"{target}.{alias}"  # from a.b import c, where c is a module
            parts = target.split(".")
            while parts and ".".join(parts) not in paths:
                parts.pop()  # the most specific module the import names
            name = ".".join(parts)
            if name and name != mod and name not in graph[mod]:
                graph[mod][name] = line
    return graph


def cycles(root: Path = ROOT) -> list[str]:
    """Return one line per import cycle between modules, naming each import on it."""
    graph = import_graph(root)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    groups: list[list[str]] = []

    def strong(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            strong(v)
    out = []
    for group in sorted(groups):
        path = _cycle_in(graph, set(group), group[0])
        pairs = zip(path, path[1:], strict=False)
        steps = [f"{a} (line {graph[a][b]}) imports {b}" for a, b in pairs]
        out.append(f"import cycle {' -> '.join(path)}: " + "; ".join(steps))
    return out


def _cycle_in(graph: dict, group: set[str], start: str) -> list[str]:
    """Return a shortest import path from ``start`` back to itself within ``group``."""
    paths = {start: [start]}
    frontier = [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(graph[v]):
                if w == start:
                    return paths[v] + [start]
                if w in group and w not in paths:
                    paths[w] = paths[v] + [w]
                    nxt.append(w)
        frontier = nxt
    raise AssertionError(f"no cycle through {start}")  # pragma: no cover


def test_imports_only_go_down_the_layers():
    found = violations()
    assert found == [], "imports that go up a layer:\n" + "\n".join(found)


def test_no_modules_import_each_other_in_a_cycle():
    found = cycles()
    assert found == [], "\n".join(found)


def _package(tmp_path: Path, files: dict[str, str]) -> Path:
    pkg = tmp_path / "zoetic"
    for name, text in {"__init__.py": "", **files}.items():
        (pkg / name).parent.mkdir(parents=True, exist_ok=True)
        (pkg / name).write_text(text)
    return pkg


def test_the_checker_catches_upward_imports_and_stray_matplotlib(tmp_path):
    pkg = _package(
        tmp_path,
        {
            "physics/step.py": "from zoetic.control import Controller\n",
            "control/lazy.py": "def f():\n    from zoetic.learning.run import Run\n",
            "tasks/plot.py": "import matplotlib.pyplot as plt\n",
            "learning/ok.py": "from zoetic.physics import simulate\nfrom . import run\n",
            "learning/rel.py": "from ..behavior import macro\n",
            "behavior/ok.py": "from zoetic.learning.optimizers import Annealing\n",
            "san/bad.py": "from zoetic.behavior.macro import search\n",
            "san/draws.py": "def f():\n    from zoetic.viz.san import plot_ranking\n",
            "physics/bench.py": "from zoetic.control import wave_controller\n",
            "learning/timing.py": "def f():\n    from zoetic.bench.simulate import run\n",
            "bench/fine.py": "from zoetic.behavior.skills import skill_figures\n",
            "viz/fine.py": "import matplotlib\nfrom zoetic.san import tune\nfrom ..runs import x\n",
            "cli/fine.py": "from zoetic.runs import finish_run\nfrom zoetic.san import tune\n",
            "behavior/up.py": "from zoetic.runs import finish_run\nfrom zoetic.san import tune\n",
            "runs.py": "def f():\n    from zoetic.viz.plots import plot_path\n",
            "gym/envs.py": "from zoetic.viz.render3d import render_frames\n",
        },
    )
    found = "\n".join(violations(pkg))
    assert "step.py:1: physics (layer 2) imports zoetic.control" in found
    assert "lazy.py:2: control (layer 4) imports zoetic.learning.run" in found
    assert "plot.py:1: imports matplotlib outside viz/" in found
    assert "rel.py:1: learning (layer 6) imports zoetic.behavior" in found
    assert "bad.py:1: san imports zoetic.behavior.macro" in found
    assert "draws.py:2: san imports zoetic.viz.san" in found  # no allowance for san -> viz
    assert "up.py:1: behavior (layer 7) imports zoetic.runs (layer 8)" in found
    assert "up.py:2: behavior imports zoetic.san (only viz and above import san)" in found
    assert "runs.py:2: runs (layer 8) imports zoetic.viz.plots (layer 9)" in found
    assert "envs.py:1: gym (layer 8) imports zoetic.viz.render3d (layer 9)" in found
    # benchmarks live in zoetic.bench, the top layer: a driver left below is checked as such
    assert "bench.py:1: physics (layer 2) imports zoetic.control" in found
    assert "timing.py:2: learning (layer 6) imports zoetic.bench.simulate (layer 10)" in found
    assert "ok.py" not in found and "fine.py" not in found


def test_the_checker_names_the_modules_of_an_import_cycle(tmp_path):
    pkg = _package(
        tmp_path,
        {
            "learning/__init__.py": "",
            "learning/a.py": "from zoetic.learning.b import g\n",
            "learning/b.py": "def g():\n    from zoetic.learning import a\n",  # a lazy import too
            "learning/c.py": "from zoetic.learning import a\n",  # leads into it: not a cycle
            "control/__init__.py": "from zoetic.control import kinds\n",
            "control/kinds.py": "from zoetic.control import load\n",  # a name of the package
            "tasks/t.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
            "    from zoetic.tasks import u\n",
            "tasks/u.py": "from zoetic.tasks import t\n",  # only a type checker sees the way back
        },
    )
    found = cycles(pkg)
    assert len(found) == 2, found
    control, learning = found
    assert control.startswith("import cycle zoetic.control -> zoetic.control.kinds -> ")
    assert "zoetic.control (line 1) imports zoetic.control.kinds" in control
    assert learning.startswith("import cycle zoetic.learning.a -> zoetic.learning.b -> ")
    assert "zoetic.learning.b (line 2) imports zoetic.learning.a" in learning
