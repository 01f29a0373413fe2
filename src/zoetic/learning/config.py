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
    extra: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """Return the settings that are set (None left out), as config.toml's [run]."""
        return {k: v for k, v in asdict(self).items() if v is not None}


def stroke_nodes(frequency: float, horizon: float, per_period: int = 4) -> int:
    """Return M, the time-domain nodes per actuator that sample a stroke of ``frequency`` Hz
    at least ``per_period`` times a period over ``horizon`` s (both ends are nodes)."""
    return int(ceil(horizon * frequency * per_period)) + 1


DEMO_BUDGET = 8000  # evaluations of ``zoetic demo``
# CMA-ES for the demo: 48 candidates a generation (96 rollouts a kernel call, from 2 starts),
# separable (the covariance's diagonal learned): 120 parameters in 8000 evaluations. Measured
# against 24 candidates with a full covariance (docs/performance.md, "Learning's own cost"):
# best E at seeds 0, 1, 2 -6.69, -6.72, -6.71 against -6.45, -6.87, -6.74, in 0.66x the CPU time
DEMO_POPSIZE = 48
DEMO_OPTIMIZER = {"diagonal": True}


def demo_config(budget: int = DEMO_BUDGET, seed: int = 0) -> LearnConfig:
    """Return the learning of ``zoetic demo``: a shark learns to swim straight from scratch
    (separable CMA-ES, 48 candidates a generation, 40 nodes per muscle)."""
    return LearnConfig(
        animal="shark",
        task="swim-straight",
        optimizer="cmaes",
        budget=budget,
        seed=seed,
        popsize=DEMO_POPSIZE,
        nodes=40,
        extra={"optimizer": dict(DEMO_OPTIMIZER)},
    )
