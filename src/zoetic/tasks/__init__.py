"""Named tasks: an objective (weighted terms), a horizon and a controller size, in TOML files."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from zoetic.errors import TaskError, ZoeticError

TASK_DIR = Path(__file__).parent
TERM_KINDS = {
    "distance_along_heading": "metres the centre of mass travelled along the start heading",
    "lateral_deviation": "squared sideways displacement of the centre of mass (m^2)",
    "depth_keeping": "mean squared change of the centre of mass's height (m^2)",
    "heading_change": "squared error of the heading change against 'target' (rad^2)",
    "goal_distance2": "squared distance of the head to 'goal', relative to its start (m^2)",
    "speed_deviation": "squared deviation of the mean forward speed from 'target' (m^2/s^2)",
}


@dataclass(frozen=True)
class Term:
    kind: str
    weight: float
    target: float = 0.0
    goal: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Task:
    """What to learn: E = mu1 * E_u + mu2 * E_v over a horizon, E_v = sum of weighted terms."""

    name: str
    description: str
    animals: tuple[str, ...]
    horizon: float
    nodes: int
    mu1: float
    mu2: float
    nu1: float
    nu2: float
    terms: tuple[Term, ...]
    source: str = "<memory>"

    def to_dict(self) -> dict:
        """Return the task as a TOML-able dict (for a run's config.toml)."""
        return {
            "name": self.name, "description": self.description, "animals": list(self.animals),
            "horizon": self.horizon, "nodes": self.nodes, "mu1": self.mu1, "mu2": self.mu2,
            "nu1": self.nu1, "nu2": self.nu2,
            "terms": [
                {"kind": t.kind, "weight": t.weight, "target": t.target, "goal": list(t.goal)}
                for t in self.terms
            ],
        }  # fmt: skip


def _num(d: dict, key: str, where: str, default=None) -> float:
    v = d.get(key, default)
    if v is None:
        raise TaskError(f"{where}: missing '{key}'")
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise TaskError(f"{where}: '{key}' must be a number, got {v!r}")
    return float(v)


def parse_task(doc: dict, source: str = "<memory>") -> Task:
    """Return the Task a parsed TOML document describes; TaskError names what is wrong."""
    where = source
    name = doc.get("name")
    if not isinstance(name, str):
        raise TaskError(f"{where}: missing 'name'")
    horizon = _num(doc, "horizon", where)
    if horizon <= 0:
        raise TaskError(f"{where}: 'horizon' must be positive, got {horizon}")
    nodes = int(_num(doc, "nodes", where, 15))
    if nodes < 2:
        raise TaskError(f"{where}: 'nodes' must be at least 2, got {nodes}")
    terms = []
    raw_terms = doc.get("terms", [])
    if not isinstance(raw_terms, list) or not raw_terms:
        raise TaskError(f"{where}: a task needs at least one [[terms]] entry")
    for k, t in enumerate(raw_terms):
        w = f"{where}: terms[{k}]"
        kind = t.get("kind") if isinstance(t, dict) else None
        if kind not in TERM_KINDS:
            raise TaskError(f"{w}: unknown kind {kind!r} (choose from {', '.join(TERM_KINDS)})")
        goal = t.get("goal", [0.0, 0.0, 0.0])
        if not (isinstance(goal, list) and len(goal) == 3):
            raise TaskError(f"{w}: 'goal' must be [x, y, z]")
        terms.append(
            Term(
                kind,
                _num(t, "weight", w, 1.0),
                _num(t, "target", w, 0.0),
                tuple(float(g) for g in goal),
            )  # fmt: skip
        )
    return Task(
        name=name,
        description=str(doc.get("description", "")),
        animals=tuple(doc.get("animals", [])),
        horizon=horizon,
        nodes=nodes,
        mu1=_num(doc, "mu1", where, 0.0),
        mu2=_num(doc, "mu2", where, 1.0),
        nu1=_num(doc, "nu1", where, 0.0),
        nu2=_num(doc, "nu2", where, 0.0),
        terms=tuple(terms),
        source=source,
    )


def list_tasks() -> list[str]:
    """Return the names of the built-in tasks."""
    return sorted(p.stem for p in TASK_DIR.glob("*.toml"))


def load_task(name_or_path: str | Path) -> Task:
    """Return a built-in task by name, or the task in a TOML file."""
    from zoetic.io import read_toml

    path = Path(name_or_path)
    if not (path.suffix == ".toml" or path.exists()):
        path = TASK_DIR / f"{name_or_path}.toml"
        if not path.exists():
            raise TaskError(
                f"unknown task {str(name_or_path)!r}: choose one of {', '.join(list_tasks())} "
                "or give the path of a task .toml file"
            )
    try:
        doc = read_toml(path, what="task file")
    except ZoeticError as exc:
        raise TaskError(str(exc)) from None
    return parse_task(doc, str(path))
