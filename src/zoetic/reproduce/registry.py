"""The claims registry: every checkable claim of the three papers, read from claims.toml.

A claim names its paper, the paper's words or number and where they are, our number, a status,
a one-line explanation, longer context for docs/reproduction.md, and either the experiment
that regenerates its figure and numbers or the reason there is none (``absent``). An
experiment is a command line (a script under experiments/ or a ``zoetic`` command) with its
quick and full arguments and the files it writes. The reader is strict: unknown keys, unknown
statuses, papers or experiments are refused with the file and entry named.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from zoetic.errors import ZoeticError
from zoetic.io import Table, load_toml, suggest

REGISTRY = Path(__file__).with_name("claims.toml")
STATUSES = ("reproduced", "partly", "contradicted", "explained", "absent")


@dataclass(frozen=True)
class Paper:
    """One of the papers the claims come from."""

    key: str
    title: str
    source: str  # the text file under /work/shared/seeds (or where the paper's text is)


@dataclass(frozen=True)
class Experiment:
    """A command that regenerates figures and numbers: ``command`` then quick or full args."""

    name: str
    command: tuple[str, ...]  # ("experiments/x.py",) or ("-m", "zoetic", "bench", ...)
    quick: tuple[str, ...]
    full: tuple[str, ...]
    outputs: tuple[str, ...]  # files it writes under the figures folder
    stdout_json: bool  # its numbers are the JSON lines it prints
    note: str


@dataclass(frozen=True)
class Claim:
    """One checkable claim and where we stand on it."""

    id: str
    paper: str
    where: str
    says: str
    ours: str
    status: str
    explanation: str
    experiment: str | None
    absent: str | None  # why no experiment regenerates it
    keys: tuple[str, ...] = ()  # "file.json:dotted.path" numbers to show from the latest run
    text: str = ""
    figures: tuple[str, ...] = field(default=())  # docs/figures files shown with the claim


@dataclass(frozen=True)
class Registry:
    """The whole registry: papers, experiments and claims, in file order."""

    papers: dict[str, Paper]
    experiments: dict[str, Experiment]
    claims: list[Claim]
    source: Path

    def claim(self, cid: str) -> Claim:
        """Return the claim ``cid``; a ZoeticError naming near ids if there is none."""
        for c in self.claims:
            if c.id == cid:
                return c
        raise ZoeticError(f"no claim {cid!r}{suggest(cid, [c.id for c in self.claims])}")


def _strings(t: Table, key: str) -> tuple[str, ...]:
    value = t.raw(key, [])
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise t.fail(f"{key!r} must be a list of strings")
    return tuple(value)


def _experiment(name: str, data: dict, where: str) -> Experiment:
    t = Table(data, f"{where}: [experiments.{name}]")
    command = _strings(t, "command")
    if not command:
        raise t.fail("'command' is empty; give the script or -m zoetic ...")
    exp = Experiment(
        name=name,
        command=command,
        quick=_strings(t, "quick"),
        full=_strings(t, "full"),
        outputs=_strings(t, "outputs"),
        stdout_json=t.boolean("stdout_json", False),
        note=t.string("note", None) or "",
    )
    t.finish()
    return exp


def _claim(data: dict, k: int, where: str, papers: dict, experiments: dict) -> Claim:
    t = Table(data, f"{where}: [[claims]] #{k + 1}")
    cid = t.string("id")
    t.where = f"{where}: claim {cid!r}"
    c = Claim(
        id=cid,
        paper=t.string("paper", choices=list(papers)),
        where=t.string("where"),
        says=t.string("says"),
        ours=t.string("ours"),
        status=t.string("status", choices=STATUSES),
        explanation=t.string("explanation"),
        experiment=t.string("experiment", None),
        absent=t.string("absent", None),
        keys=_strings(t, "keys"),
        text=(t.string("text", None) or "").strip(),
        figures=_strings(t, "figures"),
    )
    t.finish()
    if c.experiment is None and c.absent is None:
        raise t.fail("give 'experiment' (what regenerates it) or 'absent' (why nothing does)")
    if c.experiment is not None and c.experiment not in experiments:
        raise t.fail(f"unknown experiment {c.experiment!r}; known: {', '.join(experiments)}")
    return c


def load_registry(path: str | Path = REGISTRY) -> Registry:
    """Read and check the registry file (default: the package's claims.toml)."""
    path = Path(path)
    doc = Table(load_toml(path, what="claims registry"), str(path))
    papers = {}
    for key, data in doc.table("papers").data.items():
        t = Table(data, f"{path}: [papers.{key}]")
        papers[key] = Paper(key, t.string("title"), t.string("source"))
        t.finish()
    experiments = {
        name: _experiment(name, data, str(path))
        for name, data in doc.table("experiments").data.items()
    }
    claims = [
        _claim(d, k, str(path), papers, experiments) for k, d in enumerate(doc.tables("claims"))
    ]
    doc.finish()
    seen: set[str] = set()
    for c in claims:
        if c.id in seen:
            raise ZoeticError(f"{path}: claim {c.id!r} appears twice; ids must be unique")
        seen.add(c.id)
    return Registry(papers, experiments, claims, path)
