"""LearnConfig: everything that defines a learning run but the animal (written to config.toml)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from math import ceil


@dataclass
class LearnConfig:
    """A learning run's settings. ``animal`` is the animal's label (a zoo name or the file it
    came from); the body learned is the one given to ``Run.create``, stored in the run
    directory, so the label is never loaded again once a run exists."""

    animal: str = "shark"
    task: str = "swim-straight"
    optimizer: str = "cmaes"
    budget: int = 3500
    seed: int = 0
    controller: str = "periodic"
    nodes: int | None = None
    interp: str = "linear"
    popsize: int | None = None
    chains: int = 1
    evaluator: str = "batch"
    coupling: str = "auto"  # auto: "wave" for a mirror-symmetric task, else "none"
    fins: str = "auto"  # auto: "free" (learned) for a task that turns the heading, else "held"
    medium: str | None = None
    frequency: float | None = None  # periodic controller's base frequency, Hz (animal's wave)
    # where the search starts: "random" (None: uniform in the box, from the seed), "wave" (the
    # animal's own travelling wave, projected onto the controller's parameters) or "stored"
    # (the gait stored in the run directory as start.json, e.g. a hand-made repertoire entry)
    start: str | None = None
    # the plateau stop: end the run when the best E improved by at most stop_improvement times
    # |best E| over the last stop_generations generations (None: learn to the budget)
    stop_generations: int | None = None
    stop_improvement: float | None = None
    extra: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """Return the settings that are set (None left out), as config.toml's [run]."""
        return {k: v for k, v in asdict(self).items() if v is not None}


def stroke_nodes(frequency: float, horizon: float, per_period: int = 4) -> int:
    """Return M, the time-domain nodes per actuator that sample a stroke of ``frequency`` Hz
    at least ``per_period`` times a period over ``horizon`` s (both ends are nodes)."""
    return int(ceil(horizon * frequency * per_period)) + 1


DEMO_BUDGET = 2400  # evaluations of ``zoetic demo``: 50 generations of 48
# CMA-ES for the demo: 48 candidates a generation (96 rollouts a kernel call, from 2 starts),
# separable (the covariance's diagonal learned), 120 parameters, started from the shark's own
# travelling wave with a step of 0.05 of the box (docs/performance.md, "Learning in seconds"):
# from a random start the search spent about 4000 of its 8000 evaluations getting back to the
# wave's E (-5.98) and ended at -6.69, -6.72, -6.71 at seeds 0, 1, 2; from the wave, 2400
# evaluations end at -6.93, -6.89, -6.82.
DEMO_POPSIZE = 48
DEMO_OPTIMIZER = {"diagonal": True, "sigma": 0.05}
DEMO_START = "wave"


def demo_config(budget: int = DEMO_BUDGET, seed: int = 0) -> LearnConfig:
    """Return the learning of ``zoetic demo``: a shark learns to swim straight farther than
    its own travelling wave takes it (separable CMA-ES started from the wave, 48 candidates a
    generation, 40 nodes per muscle)."""
    return LearnConfig(
        animal="shark",
        task="swim-straight",
        optimizer="cmaes",
        budget=budget,
        seed=seed,
        popsize=DEMO_POPSIZE,
        nodes=40,
        start=DEMO_START,
        extra={"optimizer": dict(DEMO_OPTIMIZER)},
    )
