"""Evolution of body and network together (van de Panne & Fiume 93, section 6.3).

The paper's phase 2 tunes only the SAN's Fig. 8 parameters; its section 6.3 proposes also
changing "the link lengths, masses, and points of attachment", with the parameters
interrelated: "a stronger spring constant in the actuator ... should increase the mass of the
appropriate link. Similarly, a larger link should also have an increased mass". Here the
body's genes are, per link, a length factor and a cross-section factor, and per joint the
shift of its attachment point along the parent link (a fraction of the parent's length);
masses are never free but follow from the genes (``body_from_genes``):

    mass = m0 [(1 - MUSCLE) (length / length0) (section / section0) + MUSCLE ks / ks0]

for the child link of an actuated joint (its actuator's "muscle" is ``MUSCLE`` = 20% of the
link's starting mass and grows with the actuator's stiffness ks; ks itself is one of the
network's Fig. 8 parameters), and ``m0 (length / length0) (section / section0)`` for a link
without one: mass proportional to length x cross-section. Radii grow with the square root of
the cross-section; the moment of inertia, when the file gives one, with mass x length^2;
touch probes and link starts scale with their link's length; an anchor with its parent's
length (then the shift is added).

One annealing walk (``tune.anneal_values``, the project's ``learning.optimizers.Annealing``)
moves one parameter at a time, body genes and Fig. 8 parameters alike, and keeps the
network's weights. Every candidate body is a new MuJoCo model.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from zoetic.errors import ZoeticError
from zoetic.san.creature import Creature
from zoetic.san.network import TUNING_KEYS, Network, SanPolicy, check_fits
from zoetic.san.tune import (
    METHODS,
    Param,
    Progress,
    _network,
    _start_values,
    anneal_values,
    tunable_parameters,
)

__all__ = [
    "BOUNDS",
    "MUSCLE",
    "EvolveError",
    "EvolveResult",
    "body_from_genes",
    "changes",
    "check_evolvable",
    "evolve",
    "load_checkpoint",
    "save_checkpoint",
    "start_genes",
    "write_evolve",
]

MUSCLE = 0.2  # the share of an actuated link's starting mass that is its actuator's muscle
BOUNDS = {"length": (0.5, 2.0), "section": (0.5, 2.0), "attach": (-0.3, 0.3)}
GENES = tuple(BOUNDS)


class EvolveError(ZoeticError):
    """Evolution was asked for something it cannot do."""


def start_genes(creature: Creature) -> dict[str, np.ndarray]:
    """Return the genes of the unchanged body: factors 1, shifts 0."""
    n = len(creature.links)
    return {"length": np.ones(n), "section": np.ones(n), "attach": np.zeros(len(creature.joints))}


def _muscles(creature: Creature) -> dict[str, int]:
    """Return {link name: index of the actuator that moves it} (the child of its joint)."""
    child = {j.name: j.child for j in creature.joints}
    return {child[a.joint]: i for i, a in enumerate(creature.actuators)}


def body_from_genes(
    base: Creature, genes: dict[str, np.ndarray], ks: np.ndarray | None = None
) -> Creature:
    """Return ``base`` with the genes' lengths, sections and attachment points, its masses
    coupled to them and to the actuators' stiffness ``ks`` (default: the base's)."""
    lf = [float(v) for v in genes["length"]]
    sf = [float(v) for v in genes["section"]]
    shift = [float(v) for v in genes["attach"]]
    ks0 = np.array([a.ks for a in base.actuators], dtype=float)
    ks = ks0 if ks is None else np.asarray(ks, dtype=float)
    ks = [float(v) for v in ks]
    muscle = _muscles(base)
    links = []
    for k, ln in enumerate(base.links):
        body = lf[k] * sf[k]
        if ln.name in muscle:
            a = muscle[ln.name]
            mass = ln.mass * ((1 - MUSCLE) * body + MUSCLE * ks[a] / float(ks0[a]))
        else:
            mass = ln.mass * body
        inertia = None if ln.inertia is None else ln.inertia * (mass / ln.mass) * lf[k] ** 2
        links.append(
            replace(
                ln,
                length=ln.length * lf[k],
                start=ln.start * lf[k],
                radius=ln.radius * math.sqrt(sf[k]),
                mass=mass,
                inertia=inertia,
                depth=ln.depth * math.sqrt(sf[k]),
            )
        )
    index = {ln.name: k for k, ln in enumerate(base.links)}
    joints = []
    for j, jt in enumerate(base.joints):
        p = index[jt.parent]
        lp = links[p]
        x = jt.anchor[0] * lf[p] + shift[j] * lp.length
        x = min(max(x, lp.start), lp.start + lp.length)
        offset = jt.offset * lf[index[jt.child]]
        joints.append(replace(jt, anchor=(x, jt.anchor[1] * lf[p]), offset=offset))
    sensors = tuple(
        s if s.kind != "touch" or s.at is None else replace(s, at=s.at * lf[index[s.target]])
        for s in base.sensors
    )
    acts = tuple(replace(a, ks=ks[i]) for i, a in enumerate(base.actuators))
    return replace(base, links=tuple(links), joints=tuple(joints), sensors=sensors, actuators=acts)


def _body_params(creature: Creature, delta: float) -> list[Param]:
    n, m = len(creature.links), len(creature.joints)
    return (
        [Param("length", k, "scale", delta) for k in range(n)]
        + [Param("section", k, "scale", delta) for k in range(n)]
        + [Param("attach", j, "shift", 0.5 * delta) for j in range(m)]
    )


def _within(values: dict[str, np.ndarray]) -> bool:
    return all(
        bool(np.all((values[g] >= lo - 1e-9) & (values[g] <= hi + 1e-9)))
        for g, (lo, hi) in BOUNDS.items()
    )


def check_evolvable(creature: Creature) -> None:
    """Refuse a creature whose body evolution cannot change (slide joints: the crawler)."""
    if any(j.kind == "slide" for j in creature.joints):
        raise EvolveError(
            f"creature {creature.name!r} has slide joints; evolution changes hinged bodies only"
        )


@dataclass(frozen=True, eq=False)
class EvolveResult:
    """An evolution run: the start and the evolved body and network, metrics, history."""

    base: Creature
    creature: Creature  # evolved, with the tuned Fig. 8 values in its actuators and sensors
    network: Network  # fits ``creature`` (its tuning folded into the creature)
    start: Network
    genes: dict[str, np.ndarray]
    before: float
    after: float
    trials: int
    seed: int
    best: np.ndarray
    tried: np.ndarray
    accepted: int
    elapsed: float


class _BodyEvaluator:
    """Evaluate (network, creature) pairs, compiling a World only when the body changes."""

    def __init__(self, terrain: str, seed: int, seconds: float | None):
        self.terrain, self.seed, self.seconds = terrain, seed, seconds
        self._body: tuple | None = None
        self._world = None

    def __call__(self, network: Network, creature: Creature) -> float:
        from zoetic.san.world import World

        body = (creature.links, creature.joints)
        if self._world is None or body != self._body:
            self._world = World(creature, terrain=self.terrain, seed=self.seed)
            self._body = body
        else:
            self._world.set_tuning(creature)
        ro = self._world.run(SanPolicy(network, creature), seconds=self.seconds)
        return float(ro.metric) if np.isfinite(ro.metric) else -math.inf


def evolve(
    network: Network,
    creature: Creature,
    trials: int = 500,
    seed: int = 0,
    terrain: str = "flat",
    seconds: float | None = None,
    delta: float = 0.1,
    method: str = "anneal",
    progress: Progress | None = None,
    evaluate=None,
    resume: dict | None = None,
    checkpoint=None,
) -> EvolveResult:
    """Return the body and network evolved together by ``trials`` annealing steps.

    ``evaluate(network, creature) -> metric`` defaults to a World on ``terrain``; ``resume``
    and ``checkpoint`` as in ``tune.anneal_values``.
    """
    if method not in METHODS:
        raise EvolveError(f"unknown method {method!r}; use one of {', '.join(METHODS)}")
    if trials < 0:
        raise EvolveError("trials must be >= 0")
    check_evolvable(creature)
    check_fits(network, creature)
    evaluate = evaluate or _BodyEvaluator(terrain, seed, seconds)
    params = tunable_parameters(network, creature, delta) + _body_params(creature, delta)
    values = {**_start_values(network, creature), **start_genes(creature)}
    t0 = time.perf_counter()

    def build(v: dict[str, np.ndarray]) -> tuple[Network, Creature]:
        body = body_from_genes(creature, {g: v[g] for g in GENES}, v["ks"])
        return _network(network, v), body.with_tuning(**{k: v[k] for k in TUNING_KEYS})

    def score(v: dict[str, np.ndarray]) -> float:
        return float(evaluate(*build(v)))

    walk = anneal_values(
        values,
        params,
        score,
        method,
        trials,
        seed,
        progress,
        valid=_within,
        resume=resume,
        checkpoint=checkpoint,
    )
    net, body = build(walk.values)
    info = dict(network.info)
    info.update(evolved=method, trials=trials, seed=seed, before=walk.before, after=walk.after)
    name = f"{creature.name}-evolved"
    evolved = replace(
        body,
        name=name,
        path=None,
        description=f"{creature.name} evolved (zoetic san evolve, seed {seed})",
    )
    net = net.with_params(creature=name, tuning=None, info=info)
    return EvolveResult(
        base=creature,
        creature=evolved,
        network=net,
        start=network,
        genes={g: walk.values[g].copy() for g in GENES},
        before=walk.before,
        after=walk.after,
        trials=trials,
        seed=seed,
        best=walk.best,
        tried=walk.tried,
        accepted=walk.accepted,
        elapsed=time.perf_counter() - t0,
    )


def changes(result: EvolveResult) -> list[dict]:
    """Return the rows of the before/after table: every body parameter that evolution has,
    with the start's and the evolved creature's value."""
    a, b = result.base, result.creature
    rows = []
    for la, lb in zip(a.links, b.links, strict=True):
        rows += [
            {"parameter": f"{la.name} length (m)", "before": la.length, "after": lb.length},
            {"parameter": f"{la.name} radius (m)", "before": la.radius, "after": lb.radius},
            {"parameter": f"{la.name} mass (kg)", "before": la.mass, "after": lb.mass},
        ]
    for ja, jb in zip(a.joints, b.joints, strict=True):
        rows.append(
            {
                "parameter": f"{ja.name} anchor x on {ja.parent} (m)",
                "before": ja.anchor[0],
                "after": jb.anchor[0],
            }
        )
    for aa, ab in zip(a.actuators, b.actuators, strict=True):
        rows.append({"parameter": f"{aa.name} ks", "before": aa.ks, "after": ab.ks})
    rows.append(
        {
            "parameter": "total mass (kg)",
            "before": sum(ln.mass for ln in a.links),
            "after": sum(ln.mass for ln in b.links),
        }
    )
    for r in rows:
        r["before"], r["after"] = round(float(r["before"]), 5), round(float(r["after"]), 5)
    return rows


def write_evolve(result: EvolveResult, out, terrain: str = "flat") -> dict:
    """Write an evolve run's data: creature.toml (the evolved body, read back by the strict
    reader), san.json (its network, carrying the evolved body), start.json (carrying the
    starting body), history.csv, summary.json; return the summary. Its video is drawn by
    ``zoetic.viz.san.draw_evolve``."""
    from zoetic.io import atomic_write_bytes, write_json
    from zoetic.san.creature_file import load_creature, save_creature
    from zoetic.san.network import save_network
    from zoetic.san.search import speed_cm_s

    out = Path(out)
    path = save_creature(result.creature, out / "creature.toml")
    evolved = load_creature(path)  # the strict reader must accept what we wrote
    net = result.network.with_params(
        info={**result.network.info, "terrain": terrain, "creature_file": str(path)}
    )
    check_fits(net, evolved)
    save_network(net, out / "san.json", evolved)
    save_network(result.start, out / "start.json", result.base)
    lines = ["trial,candidate,best"] + [
        f"{i + 1},{a:.6g},{b:.6g}"
        for i, (a, b) in enumerate(zip(result.tried, result.best, strict=True))
    ]
    atomic_write_bytes(out / "history.csv", ("\n".join(lines) + "\n").encode())

    def speed(metric: float) -> float:
        return round(speed_cm_s(result.base, metric, 0.0), 2)

    summary = {
        "creature": result.base.name,
        "trials": result.trials,
        "seed": result.seed,
        "metric_before": round(result.before, 4),
        "metric_after": round(result.after, 4),
        "speed_before_cm_s": speed(result.before),
        "speed_after_cm_s": speed(result.after),
        "accepted": result.accepted,
        "seconds": round(result.elapsed, 1),
        "changes": changes(result),
        "genes": {g: [round(float(v), 4) for v in a] for g, a in result.genes.items()},
        "creature_file": str(path),
        "network": str(out / "san.json"),
    }
    write_json(out / "summary.json", summary)
    return summary


# --- checkpoints (resume) -----------------------------------------------------------------


def save_checkpoint(path, config: dict, history: dict) -> Path:
    """Write a walk's history (``tune.anneal_values``'s checkpoint) and the run's config to
    ``path`` (.npz, atomically): arrays as arrays, the rest as JSON."""
    import io
    import json

    from zoetic.io import atomic_write_bytes

    arrays, meta = {}, {"config": config}
    for key, value in history.items():
        if key == "state":
            for k, v in value.items():
                if isinstance(v, np.ndarray):
                    arrays[f"state.{k}"] = v
                else:
                    meta[f"state.{k}"] = v
        elif isinstance(value, list):
            arrays[key] = np.asarray(value, dtype=float)
        else:
            meta[key] = value
    buf = io.BytesIO()
    np.savez(buf, meta=np.array(json.dumps(meta)), **arrays)
    return atomic_write_bytes(path, buf.getvalue())


def load_checkpoint(path, config: dict) -> dict:
    """Return the history saved by ``save_checkpoint``; refuse one made with another config."""
    import json

    try:
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
            arrays = {k: z[k] for k in z.files if k != "meta"}
    except (OSError, ValueError, KeyError) as exc:
        raise EvolveError(f"{path}: not an evolve checkpoint ({exc})") from None
    saved = meta.pop("config", {})
    if saved != config:
        diff = sorted(k for k in set(saved) | set(config) if saved.get(k) != config.get(k))
        raise EvolveError(
            f"{path}: made by a different run (differs in {', '.join(diff)}); use another --out"
        )
    history: dict = {"state": {}}
    for key, value in {**meta, **arrays}.items():
        if key.startswith("state."):
            history["state"][key[6:]] = value
        else:
            history[key] = value
    return history
