"""The two ways basic training learns an entry: today's periodic controller, or the paper's.

"periodic" (the default): a constant plus two harmonics of the animal's stroke frequency per
actuator, mirror-coupled for a task that prefers neither side, learned by CMA-ES; its
harmonics are thresholded as they are (no FFT).

"paper" (Grzeszczuk & Terzopoulos 95, sections 3-4): a time-domain controller learned from
scratch, M nodal values per actuator linearly interpolated, by simulated annealing or the
simplex method; then abstracted by the FFT of its nodal values, keeping per actuator the modes
at least ``threshold`` times as strong as its strongest (the paper's "suppress the
below-threshold amplitudes", with no fallback to a lower threshold). M samples the animal's
stroke four times a period over the task's horizon (``learning.config.stroke_nodes``) unless
``nodes`` is given: the tasks' own 15 nodes cannot carry a 5 Hz stroke over 3-6 s.
"""

from __future__ import annotations

import math

from zoetic.bodies import Body
from zoetic.control import Controller
from zoetic.errors import ZoeticError
from zoetic.learning.abstraction import Abstraction, abstract, compare
from zoetic.learning.config import LearnConfig, stroke_nodes
from zoetic.learning.optimizers import OPTIMIZERS
from zoetic.tasks import Task

PIPELINES = ("periodic", "paper")
PAPER_OPTIMIZERS = ("anneal", "simplex")  # the two the paper compares (its Fig. 6)
PAPER_OPTIMIZER = "anneal"  # the paper's choice for its repertoires


def check_training(pipeline: str, optimizer: str | None, threshold: float) -> str:
    """Return the optimizer the pipeline learns with (None: the pipeline's own default);
    ZoeticError for an unknown pipeline, an unknown optimizer, one the paper's pipeline does
    not use, or a threshold outside (0, 1]."""
    if pipeline not in PIPELINES:
        raise ZoeticError(f"--pipeline must be one of {', '.join(PIPELINES)}, got {pipeline!r}")
    if optimizer is not None and optimizer not in OPTIMIZERS:
        raise ZoeticError(f"--optimizer must be one of {', '.join(OPTIMIZERS)}, got {optimizer!r}")
    if not (math.isfinite(threshold) and 0.0 < threshold <= 1.0):
        raise ZoeticError(
            f"--threshold must be in (0, 1] (a fraction of each actuator's strongest mode), "
            f"got {threshold}"
        )
    if pipeline == "paper":
        if optimizer is not None and optimizer not in PAPER_OPTIMIZERS:
            raise ZoeticError(
                f"--pipeline paper learns with {' or '.join(PAPER_OPTIMIZERS)} (the paper's "
                f"optimizers), not {optimizer!r}"
            )
        return optimizer or PAPER_OPTIMIZER
    return optimizer or "cmaes"


def entry_config(pipeline: str, body: Body, task: Task, nodes: int | None) -> dict:
    """Return the LearnConfig settings the pipeline adds for one entry (controller, nodes)."""
    if pipeline == "paper":
        m = nodes or stroke_nodes(body.wave_frequency, task.horizon)
        return {"controller": "time", "nodes": m}
    return {"nodes": nodes}


def check_resumed(pipeline: str, config: LearnConfig, where: str) -> None:
    """Refuse to continue an entry learned by the other pipeline (its controller family)."""
    paper = config.controller == "time"
    if paper != (pipeline == "paper"):
        was = "paper" if paper else "periodic"
        raise ZoeticError(
            f"{where}: this entry was learned by --pipeline {was}; continue it with "
            f"--pipeline {was}, or train into a fresh --out"
        )


def paper_abstraction(
    body: Body,
    original: Controller,
    task: Task,
    modes: str | int,
    threshold: float,
    optimizer: str,
) -> tuple[Abstraction, dict]:
    """Return the FFT abstraction of a learned time-domain controller (``modes`` "auto": the
    modes at least ``threshold`` times each actuator's strongest; K: the K strongest) and
    the entry metadata that says where it came from: the pipeline, the optimizer, the modes
    kept per actuator and in all, and the fractions of the distance (centre of mass, top
    view) and of the task's primary measure the abstraction keeps, played from the task's
    start state over its horizon."""
    ab = abstract(original, modes, threshold)
    cmp = compare(body, original, ab.controller, task)
    o, a = cmp.original["distance"], cmp.abstract["distance"]
    info = {
        "pipeline": "paper",
        "optimizer": optimizer,
        "learned_nodes": getattr(original, "nodes", None),
        "modes_kept": int(ab.modes_per_actuator().sum()),
        "distance_kept": round(float(a / o), 4) if o > 1e-9 else None,
        "task": task.name,
        "rule": ab.rule,
        "modes_per_actuator": ab.modes_per_actuator().tolist(),
        "frequencies_hz": sorted(
            {round(float(f), 4) for f in ab.controller.freq[ab.controller.amp > 0]}
        ),
        **cmp.to_dict(),
    }
    return ab, info
