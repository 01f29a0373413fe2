"""Entries that keep their promises: a learned entry that breaks a promise of its task is
learned again from a seed derived from its own, up to ``RESTARTS`` times.

A restart is a new draw of the same search (CMA-ES from another random start, the same
budget): it helps when the first search ended in a poor local optimum (a sharp turn of 89.8
degrees where 90 are promised, a turn that rolls the animal over). The first restart that
keeps every promise replaces the entry; when none does, the try that breaks least
(``shortfall``) does, the first one included. The entry's repertoire info says why it was
restarted, each try's run and seed, and which was kept ("restarts").

An entry whose task promises what the animal cannot do is not restarted: no seed changes
physics (``beyond_reach``). The one bound checked is the climb: a rise or sink the promise
asks is out of reach from a start when the animal's straight swim (its fastest learned entry,
``STRAIGHT``) covers a shorter straight line than that over the task's horizon from that
start (even pointed straight up from the first instant it would rise less), and an entry must
keep its promises from every start (the ray's disc: docs/animals.md, "Depth").

Restart runs live beside the entry's own (``runs/<entry>.restart<n>``), each checkpointed
and resumed like it; the seeds and the choice depend only on the training's seed, so the
same seed gives the same repertoire, and a seed whose entries keep every promise gives the
repertoire it gave without restarts.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from zoetic.behavior.promises import entry_motion, judge_entry, outside, unmet_text
from zoetic.bodies import Body
from zoetic.control import Controller
from zoetic.learning.abstraction import Abstraction
from zoetic.learning.blas import one_blas_thread
from zoetic.tasks import Promise, Task

if TYPE_CHECKING:
    from zoetic.behavior.training import Entry
    from zoetic.learning.run import Run

# restarts at most of an entry that breaks a promise (each costs its budget again)
RESTARTS = 2
# the plan's straight swims (``training.PLAN``, ``SURFACE_PLAN``): the animal's fastest entries
STRAIGHT = ("go-straight", "move-forward")

Learned = tuple[Abstraction, dict]  # an entry's abstraction and its repertoire info


def restart_seed(seed: int, attempt: int) -> int:
    """Return the seed of an entry's ``attempt``-th restart, derived from the entry's own
    ``seed`` (``numpy.random.SeedSequence``: unrelated to any other entry's or seed's)."""
    return int(np.random.SeedSequence([seed % 2**63, attempt]).generate_state(1)[0])


def shortfall(task: Task, verdict: dict) -> tuple[int, float]:
    """Return how much an entry breaks its task's promises (``judge_entry``'s verdict): the
    number broken, then the sum of each one's miss over the bound it misses (a miss of a
    bound at 0 counted as is); less is better."""
    misses = [
        _relative_miss(p, float(o["worst"]))
        for p, o in zip(task.promises, verdict["promises"], strict=True)
        if not o["met"]
    ]
    return len(misses), float(sum(misses))


def _relative_miss(p: Promise, value: float) -> float:
    """Return how far ``value`` lies outside the promise as a fraction of the bound missed."""
    if not np.isfinite(value):
        return float("inf")
    bound = p.low if value < p.low else p.high
    return max(outside(p, value), 0.0) / (abs(bound) if np.isfinite(bound) and bound else 1.0)


def beyond_reach(body: Body, task: Task, straight: Controller | None) -> str | None:
    """Return why no controller can keep ``task``'s climb promise from one of its starts (the
    least rise or sink it asks is more than the straight-line distance the animal's straight
    swim ``straight`` covers over the horizon from that start), or None when nothing known
    forbids it."""
    climbs = [p for p in task.promises if p.quantity == "climb_m"]
    if straight is None or not climbs or climbs[0].low <= 0.0 <= climbs[0].high:
        return None
    p = climbs[0]
    least = min(abs(p.low), abs(p.high))
    rows = entry_motion(body, straight, task)
    for start, row in zip(task.start_names(), rows, strict=True):
        if row["distance_m"] < least:
            return (
                f"{p.text()} is beyond reach: its straight swim covers {row['distance_m']:.3g} m "
                f"in {task.horizon:g} s from {start}"
            )
    return None


def keep_promises(
    body: Body,
    entries: list[Entry],
    runs: list[Run],
    learned: list[Learned],
    again: Callable[[Entry, Run], Learned],
    resume: Callable[[Path, Entry], Run],
    out: Path,
    on_entry: Callable[[str, object], None] | None = None,
    progress: Callable[[object], None] | None = None,
) -> list[tuple[Entry, Learned]]:
    """Judge each learned entry (``learned``: its abstraction and info, in plan order);
    restart the ones that break a promise within reach (module doc), a round's restarts
    learned together; return, in plan order, the entries that break a promise, each with the
    abstraction and info to keep (info["restarts"] says why and what was tried).

    again(entry, run) abstracts a restart's run as ``learned`` was; resume(run_dir, entry)
    continues a restart run begun in run_dir; on_entry and progress are
    ``train_repertoire``'s (a restart's line is named "<entry> restart <n>")."""
    from zoetic.learning.together import learn_together

    pairs = list(zip(entries, learned, strict=True))
    with one_blas_thread():  # judging and the reach bound: small linear algebra
        verdicts = [judge_entry(body, ab.controller, e.task) for e, (ab, _) in pairs]
        tries, changed = _first_tries(body, entries, runs, learned, verdicts)
    pending = list(tries)
    for attempt in range(1, RESTARTS + 1):
        if not pending:
            break
        new = [(i, _restart_run(entries[i], runs[i], attempt, body, out, resume)) for i in pending]
        for i, run in new:
            if on_entry:
                on_entry(f"{entries[i].name} restart {attempt}", run)
        learn_together([run for _, run in new], progress=progress)
        with one_blas_thread():
            for i, run in new:
                ab, info = again(entries[i], run)
                verdict = judge_entry(body, ab.controller, entries[i].task)
                tries[i].append(((ab, info), verdict, run.setup.config.seed))
        pending = [i for i in pending if not tries[i][-1][1]["met"]]
    for i, tried in tries.items():
        changed[i] = _choose(entries[i], tried)
    return [(entries[i], changed[i]) for i in sorted(changed)]


def _first_tries(
    body: Body, entries: list[Entry], runs: list[Run], learned: list[Learned], verdicts: list[dict]
) -> tuple[dict[int, list[tuple[Learned, dict, int]]], dict[int, Learned]]:
    """Return, by plan index, the first try of each entry to restart (its abstraction and
    info, verdict and seed) and the entries kept as they are with why they were not restarted
    (a promise beyond reach, ``beyond_reach``)."""
    # the reach bound from a straight swim that keeps its own promises only: a poor one
    # (what restarts are for) would call reachable climbs out of reach
    straight = next(
        (
            ab.controller
            for e, (ab, _), v in zip(entries, learned, verdicts, strict=True)
            if e.name in STRAIGHT and v["met"]
        ),
        None,
    )
    tries: dict[int, list[tuple[Learned, dict, int]]] = {}
    changed: dict[int, Learned] = {}
    for i, (entry, verdict) in enumerate(zip(entries, verdicts, strict=True)):
        if verdict["met"]:
            continue
        reason = beyond_reach(body, entry.task, straight)
        if reason:
            ab, info = learned[i]
            record = {"because": unmet_text(entry.name, verdict), "skipped": reason}
            changed[i] = (ab, info | {"restarts": record})
        else:
            tries[i] = [(learned[i], verdict, runs[i].setup.config.seed)]
    return tries, changed


def _restart_run(
    entry: Entry,
    run: Run,
    attempt: int,
    body: Body,
    out: Path,
    resume: Callable[[Path, Entry], Run],
) -> Run:
    """Return the ``attempt``-th restart of an entry's learning ``run``: the same settings
    from a derived seed (``restart_seed``) in ``runs/<entry>.restart<attempt>``, or the one
    begun there (an interrupted training), continued by ``resume``."""
    from zoetic.learning.run import Run

    run_dir = out / "runs" / f"{entry.name}.restart{attempt}"
    if (run_dir / "config.toml").exists():
        return resume(run_dir, entry)
    config = run.setup.config
    seed = restart_seed(config.seed, attempt)
    return Run.create(run_dir, dataclasses.replace(config, seed=seed), body)


def _choose(entry: Entry, tried: list[tuple[Learned, dict, int]]) -> Learned:
    """Return the try to keep (the first restart keeping every promise, else the one that
    breaks least, the first try winning ties) with its info's "restarts" record."""
    met = [k for k, (_, v, _) in enumerate(tried) if v["met"] and k > 0]
    k = met[0] if met else min(range(len(tried)), key=lambda j: shortfall(entry.task, tried[j][1]))
    (ab, info), _, _ = tried[k]
    record = {
        "because": unmet_text(entry.name, tried[0][1]),
        "tries": [
            {
                "run": learned[1]["source"],
                "seed": seed,
                "met": verdict["met"],
                "broken": [o["promise"] for o in verdict["promises"] if not o["met"]],
            }
            for learned, verdict, seed in tried
        ],
        "kept": info["source"],
    }
    return ab, info | {"restarts": record}
