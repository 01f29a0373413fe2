"""Stunts (section 3.2, Plate 5): macro controllers searched for a trick's style terms.

A trick (``behavior.tricks``) is a task file with a plan's shape and the world's objects: a
hurdle's bar, a beach ball on its post; its style terms (``zoetic.tasks.terms``) here also see
the World's contact record and the balls (``behavior.stunt_problem``).

A plan, as for ``behavior.macro``, is a sequence of repertoire entries with durations, played
cross-faded (5%); the same searches (simulated annealing on ``learning.optimizers.Annealing``, or
the genetic algorithm) look for the plan of least E = sum of weighted terms, every batch of
plans simulated as one World (the animal in B copies beside the trick's objects).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.stunt_measures import measures
from zoetic.behavior.stunt_problem import (
    CHECK_SIGNS,
    StuntProblem,
    StuntRecord,
    jittered_starts,
    starts_per_plan,
)
from zoetic.behavior.tricks import Trick, parse_object

# re-exported: the stunt commands and experiments find the trick files here
from zoetic.behavior.tricks import list_tricks as list_tricks
from zoetic.behavior.tricks import load_trick as load_trick
from zoetic.behavior.tricks import parse_trick as parse_trick
from zoetic.bodies import Body
from zoetic.control.abstract import SequenceController
from zoetic.errors import TaskError
from zoetic.io import read_json
from zoetic.learning.blas import one_blas_thread
from zoetic.physics import Trajectory
from zoetic.physics.objects import Ball, Box, Cylinder
from zoetic.tasks.terms import (
    TAIL_STRIKE_TURN,
)

MACRO_FORMAT = "zoetic-stunt-macro"


# the targets, per built-in trick (bellyflop against clean-dive: ``splash_ratio``)
LEAP_AIR_S, LEAP_APEX_BL, SOMERSAULT_DEG, SPLASH_RATIO = 0.4, 0.5, 360.0, 3.0
SPIN_DEG = 360.0  # spin: a full turn about the body's own long axis in the air
BUDGET = 9600  # stunt simulations a trick search runs by default (about a minute on 2 cores)
TAIL_STRIKE_DEG = float(np.degrees(TAIL_STRIKE_TURN))  # ball-tail: a strike after half a turn
# the tricks ``targets_met`` has targets for
TARGET_TRICKS = (
    "leap", "hurdle", "somersault", "spin", "bellyflop", "clean-dive", "ball-nose", "ball-tail"
)  # fmt: skip
STOP_CHECK_EVERY = 4  # batches at least between two checks of the search's best plan


def targets_met(name: str, m: dict, trick: Trick | None = None) -> dict[str, bool]:
    """Return the success flags of a built-in trick's measures (``measures``) against the
    issue's targets; {} for a trick of another name. Bellyflop and clean-dive need to leave
    the water and be wholly back in it by the end (a splash not yet made is not small); their
    target is the ratio of their splashes (``splash_ratio``). A trick's own targets
    (``Trick.targets``) add a flag each: the measure reported and within its [min, max]."""
    flags: dict[str, bool] = {}
    if name in ("leap", "hurdle", "somersault", "spin", "bellyflop", "clean-dive"):
        flags["leaves_water"] = bool(m["most_nodes_out_of_water"] >= 1.0)
    if name == "leap":
        flags["air_time"] = bool(m["air_time_s"] >= LEAP_AIR_S)
        flags["apex"] = bool(m["apex_body_lengths"] >= LEAP_APEX_BL)
    elif name in ("bellyflop", "clean-dive"):
        flags["back_in_water"] = bool(m.get("final_height_m", 1.0) == 0.0)
    elif name == "somersault":
        # a full turn about the body's own left-right axis (a spin about the vertical is none)
        flags["rotation"] = bool(m["pitch_rotation_in_air_deg"] >= SOMERSAULT_DEG)
    elif name == "spin":
        flags["rotation"] = bool(m["roll_rotation_in_air_deg"] >= SPIN_DEG)
    elif name == "hurdle":
        flags["over_bar"] = bool(m.get("bar_crossed", False))
        flags["no_contact"] = not m.get("hurdle_touched", True)
    elif name in ("ball-nose", "ball-tail"):
        part = "nose" if name == "ball-nose" else "tail"
        radius = next(
            (o.radius for o in (trick.objects if trick else ()) if isinstance(o, Ball)), 0.0
        )
        # off its support: the ball moved more than its radius after that part struck it
        flags[f"struck_by_{part}"] = part in m.get("ball_parts", [])
        flags["off_support"] = bool(m.get(f"ball_moved_by_{part}_m", 0.0) > radius)
        if part == "tail":  # during a somersault: out of the water, half a turn or more done
            flags["in_somersault"] = bool(m.get("tail_strike_rotation_deg", 0.0) >= TAIL_STRIKE_DEG)
    for key, lo, hi in trick.targets if trick else ():
        if key not in m:  # a misspelt target could never be met: say so, not "not met"
            known = ", ".join(sorted(k for k, v in m.items() if isinstance(v, (int, float))))
            raise TaskError(
                f"trick {trick.name!r}: [trick.targets] {key!r} is not a measure of a stunt; "
                f"choose from {known}"
            )
        value = m[key]  # None: not measured this time (no re-entry), so not met
        flags[key] = value is not None and bool(lo <= value <= hi)
    return flags


def perturbed_measures(
    problem: StuntProblem, entries: np.ndarray, durations: np.ndarray, signs=CHECK_SIGNS
) -> list[dict]:
    """Return ``measures`` of a plan played from each start moved by ``signs`` (K, 3) x the
    trick's jitter (depth m, heading and pitch deg; default: one at a time, each way),
    recorded as a found stunt is (every other time step)."""
    starts = jittered_starts(problem.trick, problem.body, signs)
    rec = problem.record(entries[None], durations[None], record_every=2, starts=starts)
    return [measures(problem, rec, lane) for lane in range(len(signs))]


def perturbed_successes(
    problem: StuntProblem, entries: np.ndarray, durations: np.ndarray, signs=CHECK_SIGNS
) -> list[bool]:
    """Return whether a plan still meets its trick's targets (``targets_met``) from each
    start moved by ``signs`` (``perturbed_measures``)."""
    trick = problem.trick
    return [
        all(targets_met(trick.name, m, trick).values())
        for m in perturbed_measures(problem, entries, durations, signs)
    ]


class StopWhenMet:
    """The stop rule of a ``stop_when_met`` trick's search: true once the search's best plan
    meets the trick's targets (``targets_met``) from the start and from each of the check's
    perturbed starts (``CHECK_SIGNS``; the start alone without a jitter). Asked after every
    batch, it replays a best plan that improved since its last check, at most once every
    ``every`` batches (a check is 7 stunts, a seventh of a robust batch of 16 plans)."""

    def __init__(self, problem: StuntProblem, every: int = STOP_CHECK_EVERY):
        self.problem, self.every = problem, int(every)
        jitter = any(problem.trick.jitter)
        self.signs = ((0, 0, 0), *CHECK_SIGNS) if jitter else ((0, 0, 0),)
        self.waited, self.checked_f, self.checks = 0, np.inf, 0

    def __call__(self, opt) -> bool:
        self.waited += 1
        if not opt.best_f < self.checked_f or self.waited < self.every:
            return False
        self.waited, self.checked_f = 0, opt.best_f
        self.checks += 1
        e, d = opt.best
        return all(perturbed_successes(self.problem, e, d, self.signs))


def splash_ratio(bellyflop: dict, clean_dive: dict) -> float | None:
    """Return the bellyflop's splash measure over the clean dive's, both ``measures``; None
    unless both left the water wholly and the dive splashed at all (a body that only broke the
    surface from below, or one still in the air at the end, makes no re-entry to compare)."""
    both = all(
        m["most_nodes_out_of_water"] >= 1.0 and m.get("final_height_m", 0.0) == 0.0
        for m in (bellyflop, clean_dive)
    )
    a, b = bellyflop["splash_m3_s"], clean_dive["splash_m3_s"]
    return float(a / b) if both and b > 0 else None


def macro_document(problem: StuntProblem, sequence: SequenceController, trick_source: str) -> dict:
    """Return macro.json's content: the controller, the trick, the start state, the duration."""
    return {
        "format": MACRO_FORMAT,
        "animal": problem.body.name,
        "trick": trick_source,
        "seconds": problem.steps * problem.body.dt,
        "start": {
            "positions": problem.start.positions[0].tolist(),
            "velocities": problem.start.velocities[0].tolist(),
        },
        "objects": problem.trick.to_dict()["objects"],
        "controller": sequence.to_dict(),
    }


def is_macro_file(path: str | Path) -> bool:
    """Return True when ``path`` is a stunt's macro.json (a file that cannot be read is not:
    the controller reader then says what is wrong with it)."""
    from zoetic.errors import ZoeticError
    from zoetic.io import load_json

    p = Path(path)
    if p.suffix != ".json" or not p.is_file():
        return False
    try:
        doc = load_json(p, "controller file")
    except ZoeticError:
        return False
    return isinstance(doc, dict) and doc.get("format") == MACRO_FORMAT


def load_macro(path: str | Path, body: Body) -> tuple[SequenceController, dict]:
    """Return the controller of a macro.json (checked against the body) and the document."""
    from zoetic.control import check_fits as controller_fits
    from zoetic.control import from_dict

    doc = read_json(path, what="stunt macro file")
    try:
        ctrl = controller_fits(from_dict(doc["controller"], where=str(path)), body, str(path))
        pos = np.asarray(doc["start"]["positions"], float)
        vel = np.asarray(doc["start"]["velocities"], float)
        seconds = float(doc["seconds"])
        objects = tuple(
            parse_object(o, f"{path}: objects[{k}]") for k, o in enumerate(doc["objects"])
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise TaskError(f"{path}: malformed stunt macro file ({exc})") from None
    if pos.shape != (body.n_nodes, 3) or vel.shape != pos.shape:
        raise TaskError(
            f"{path}: the start state is for {pos.shape[0]} nodes; the "
            f"{body.name} has {body.n_nodes}"
        )
    return ctrl, {"seconds": seconds, "positions": pos, "velocities": vel, "objects": objects}


def replay(
    body: Body, path: str | Path, seconds: float | None = None, record_every: int = 2
) -> tuple[Trajectory, np.ndarray]:
    """Replay a macro.json from its start state among its objects; return the trajectory and
    the balls' positions (R, nb, 3)."""
    from zoetic.control.policy import OpenLoopPolicy
    from zoetic.control.rollout import rollout
    from zoetic.physics.world import World

    ctrl, info = load_macro(path, body)
    seconds = float(info["seconds"] if seconds is None else seconds)
    w = World([body, *info["objects"]], medium=body.medium, batch=1)
    st = w.initial_state()
    w.restore(
        dataclasses.replace(
            st, positions=(info["positions"][None],), velocities=(info["velocities"][None],)
        )
    )
    ro = rollout(
        w, OpenLoopPolicy(ctrl), seconds, control_period=seconds, record_every=record_every
    )
    return ro.trajectory(0), ro.ball_positions[0]


def score_series(problem: StuntProblem, rec: StuntRecord, lane: int = 0) -> dict[str, np.ndarray]:
    """Return what the style terms read over time (R,) for one stunt, by label."""
    s = problem.signals(rec)
    out = {
        "COM above surface (m)": s.com[lane, :, 1] - problem.level,
        "nodes out of water": np.mean(1.0 - s.in_water[lane], axis=1),
        "body angle (deg)": np.degrees(s.body_angle[lane]),
        "contacts (cumulative)": np.cumsum(rec.contacts[lane]),
        "splash (cumulative, m^3/s)": np.concatenate(
            [[0.0], np.cumsum(s.entry_flux[lane].sum(axis=1))]
        ),
    }
    if rec.balls.shape[2]:
        out["ball height (m)"] = rec.balls[lane, :, 0, 1]
    return out


def object_markers(objects, balls: np.ndarray, spacing: float = 0.08) -> np.ndarray:
    """Return (R, M, 3) points to draw the objects with: fixed shapes sampled along their
    long axis (a bar, a post; a box's centre), the balls where they are at each record."""
    balls = np.asarray(balls, float)
    fixed = []
    for o in objects:
        if isinstance(o, Cylinder):
            n = max(2, int(np.ceil(o.length / spacing)) + 1)
            pts = np.tile(np.asarray(o.center, float), (n, 1))
            pts[:, "xyz".index(o.axis)] += np.linspace(-o.length / 2, o.length / 2, n)
            fixed.append(pts)
        elif isinstance(o, Box):
            fixed.append(np.asarray(o.center, float)[None])
    fix = np.concatenate(fixed) if fixed else np.zeros((0, 3))
    r = balls.shape[0]
    return np.concatenate([balls.reshape(r, -1, 3), np.broadcast_to(fix, (r, *fix.shape))], axis=1)


@dataclass
class Stunt:
    """A discovered stunt: the search's result, its problem, and its best plan re-recorded."""

    problem: StuntProblem
    result: object  # behavior.macro.MacroResult
    record: StuntRecord  # the best plan, recorded every other time step
    scores: dict  # its E ('cost') and term values (B = 1)
    measures: dict  # measures() of it
    # the plan's targets met from each of the check's perturbed starts (``CHECK_SIGNS``); empty
    # for a trick without a jitter
    perturbed: list[bool] = dataclasses.field(default_factory=list)

    def summary(self) -> dict:
        """Return the JSON-able numbers of the stunt (without the search history)."""
        r, seconds = self.result, self.problem.steps * self.problem.body.dt
        starts = r.sequence.starts()
        return {
            "animal": self.problem.body.name,
            "trick": self.problem.trick.name,
            "trick_file": self.problem.task.source,
            "method": r.method,
            "seconds": seconds,
            **self.measures,
            "E": round(float(self.scores["cost"][0]), 5),
            "terms": {k: round(float(v[0]), 5) for k, v in self.scores.items() if k != "cost"},
            "plan": [
                {
                    "entry": n,
                    "start_s": round(float(t), 3),
                    "duration_s": round(float(d), 3),
                    "played": bool(t < seconds),
                }
                for n, t, d in zip(r.names, starts, r.durations, strict=True)
            ],
            "evaluations": r.evaluations,
            "stopped_when_met": r.stopped,
            "wall_s": round(r.wall, 2),
            "jitter": self.problem.trick.to_dict()["jitter"],
            "perturbed_starts_met": sum(self.perturbed),
            "perturbed_starts": len(self.perturbed),
        }


def discover(
    body: Body,
    repertoire: Repertoire,
    trick: Trick,
    method: str = "anneal",
    budget: int = BUDGET,
    seed: int = 0,
    segments: int | None = None,
    progress=None,
    evaluator: str = "batch",
) -> Stunt:
    """Return the best stunt ``method`` (anneal: 16 chains; ga: 32 a generation) finds for the
    trick within ``budget`` stunt simulations (plans x the starts each is played from: 3 for a
    robust trick, else 1).

    ``evaluator``: batch (this process) or ray (each batch of plans on Ray actors, the problem
    put in the object store once; same seed, same stunt as in process). A ``stop_when_met``
    trick with targets ends its search once they are met from every checked start
    (``StopWhenMet``)."""
    from zoetic.behavior.macro import search

    problem = StuntProblem(body, repertoire, trick, segments)
    # the budget counts stunt simulations: a robust search plays each plan from K starts
    plans = max(1, budget // starts_per_plan(trick))
    opts = {"chains": min(16, plans)} if method == "anneal" else {"popsize": min(32, plans)}
    stop = StopWhenMet(problem) if trick.stop_when_met and trick.name in TARGET_TRICKS else None
    result = search(
        problem, method, plans, seed, progress=progress, evaluator=evaluator, stop=stop, **opts
    )
    with one_blas_thread():  # the replay's and the moved starts' small products
        rec = problem.record(result.entries[None], result.durations[None], record_every=2)
        checked = (
            perturbed_successes(problem, result.entries, result.durations)
            if any(trick.jitter)
            else []
        )
    return Stunt(problem, result, rec, problem.scores(rec), measures(problem, rec), checked)
