"""The figures of ``zoetic bench all``'s table: where each is read in the benchmarks' JSON,
what it is measured against in the same run, and the papers' figures where they give one.

Papers (/work/shared/seeds; their figures quoted in :data:`PAPERS`):
000: Grzeszczuk and Terzopoulos, Automated Learning of Muscle-Actuated Locomotion Through
Control Abstraction (1995); 001: van de Panne and Fiume, Sensor-Actuator Networks (1993);
003: Terzopoulos, Rabie and Grzeszczuk, Perception and Learning in Artificial Animals.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

AQUARIUM_FRAME_S = 0.05  # simulated seconds per frame of zoetic aquarium's record and video


@dataclass(frozen=True)
class Paper:
    """A paper's figure: its value in the figure's unit, the paper and host, and its words."""

    value: float
    source: str
    quote: str


PAPERS = {
    "anneal": Paper(
        3600.0,
        "paper 000, SGI Indigo",
        "'For N=15 it takes about one hour ... to get a solution for each control function'",
    ),
    "san": Paper(
        1200.0 / (6 * 3600.0),
        "paper 001, Sun SPARC IPC",
        "'200 controllers ... 1200 seconds of simulation ... 6 hours for the walker'",
    ),
    "tank": Paper(
        4.0,
        "paper 003, SGI Indigo2, drawn",
        "'10 fishes, 15 food particles, and 5 static obstacles at about 4 frames/sec "
        "(with wireframe rendering)'",
    ),
}


@dataclass(frozen=True)
class Figure:
    """One figure of the table. ``value(results)`` reads it from ``{bench key: its JSON}``
    (None: not measured); ``baseline`` the same run's side-by-side reference; ``higher``
    whether more is faster (a rate) or less (a time); ``sized``: a time for a fixed amount of
    work, compared with the paper's only at full sizes."""

    key: str
    label: str
    unit: str
    value: Callable[[dict], Any]
    higher: bool = True
    baseline: Callable[[dict], Any] | None = None
    baseline_label: str = ""
    paper: Paper | None = None
    sized: bool = False

    @property
    def bench(self) -> str:
        """The key of the benchmark whose JSON holds the figure: its key's first part."""
        return self.key.split(".")[0]


def at(bench: str, *path: str) -> Callable[[dict], Any]:
    """A reader of ``results[bench][path[0]][path[1]]...`` (None where anything is missing)."""

    def read(results: dict) -> Any:
        v: Any = results.get(bench)
        for key in path:
            v = v.get(key) if isinstance(v, dict) else None
        return v

    return read


def _leaves(tree: Any, key: str) -> list:
    """Every value under ``key`` anywhere in a nested JSON dict."""
    if not isinstance(tree, dict):
        return []
    here = [tree[key]] if key in tree else []
    return here + [v for sub in tree.values() for v in _leaves(sub, key)]


def total(bench: str, key: str, fn: Callable = sum) -> Callable[[dict], Any]:
    """A reader of ``fn`` over every ``key`` in the bench's JSON (None when there is none)."""

    def read(results: dict) -> Any:
        found = [v for v in _leaves(results.get(bench), key) if isinstance(v, int | float)]
        return round(fn(found), 3) if found else None

    return read


def count(bench: str, key: str) -> Callable[[dict], str | None]:
    """A reader of 'true/all' over every boolean ``key`` in the bench's JSON."""

    def read(results: dict) -> str | None:
        found = [v for v in _leaves(results.get(bench), key) if isinstance(v, bool)]
        return f"{sum(found)}/{len(found)}" if found else None

    return read


def _jax_on(device: str) -> Callable[[dict], Any]:
    """The JAX bench's sim-s/s on the CPU or a GPU ("no GPU" when JAX ran on the CPU only)."""

    def read(results: dict) -> Any:
        # zoetic bench jax prints {"jax": its figures, "numba": ... with --numba}
        run = (results.get("jax") or {}).get("jax") or {}
        cpu = (results.get("jax-cpu") or {}).get("jax")
        on_cpu = run.get("backend", "cpu") == "cpu"
        if device == "cpu":
            run = cpu if cpu is not None else run if on_cpu else {}
        elif on_cpu:
            return "no GPU" if "backend" in run else None
        return run.get("sim_seconds_per_second_batched")

    return read


def _tank_frames(results: dict) -> float | None:
    rtf = at("aquarium", "realtime_factor")(results)
    return None if rtf is None else rtf / AQUARIUM_FRAME_S


def _slowest_trick(results: dict) -> float | None:
    out = results.get("stunts")
    walls = [v["wall_s"] for v in (out or {}).values() if isinstance(v, dict) and "wall_s" in v]
    return max(walls) if walls else None


NUMBA = at("simulate", "sim_seconds_per_second_batched")
ANNEAL = at("learn", "anneal_seconds")
FIGURES: tuple[Figure, ...] = (
    Figure(
        "simulate.batched",
        "shark batched, all cores",
        "sim-s/s",
        NUMBA,
        baseline=at("simulate", "numpy_reference_sim_seconds_per_second"),
        baseline_label="NumPy reference, this run",
    ),
    Figure(
        "simulate.single",
        "shark, one candidate",
        "sim-s/s",
        at("simulate", "sim_seconds_per_second_single"),
    ),
    Figure(
        "learn.anneal",
        "anneal, 3500 evaluations (quick 300)",
        "s",
        ANNEAL,
        higher=False,
        paper=PAPERS["anneal"],
        sized=True,
    ),
    Figure(
        "learn.cmaes",
        "CMA-ES to anneal's E",
        "s",
        at("learn", "cmaes_seconds_to_match_anneal"),
        higher=False,
        baseline=ANNEAL,
        baseline_label="anneal, this run",
        sized=True,
    ),
    Figure(
        "learn.gradient",
        "gradient to anneal's E (compile apart)",
        "s",
        at("learn", "gradient_seconds_to_match_anneal"),
        higher=False,
        baseline=ANNEAL,
        baseline_label="anneal, this run",
        sized=True,
    ),
    Figure(
        "learn.gradient_compile",
        "gradient: JAX compile",
        "s",
        at("learn", "gradient_compile_seconds"),
        higher=False,
    ),
    Figure(
        "learn.gradient_compile_cached",
        "gradient: JAX compile, cached (a later run)",
        "s",
        at("learn", "gradient_compile_seconds_cached"),
        higher=False,
    ),
    Figure(
        "train.demo",
        "demo learning, 2400 evals (quick 400)",
        "s",
        at("train", "demo_learning_seconds"),
        higher=False,
        sized=True,
    ),
    Figure(
        "train.repertoire",
        "repertoire train shark (quick 150/entry)",
        "s",
        at("train", "repertoire_train_seconds"),
        higher=False,
        sized=True,
    ),
    Figure(
        "skills.wall",
        "skills: learning them all",
        "s",
        total("skills", "learn_wall_s"),
        higher=False,
        sized=True,
    ),
    Figure(
        "skills.beats",
        "skills: learned beats hand-made",
        "",
        count("skills", "learned_beats_hand_made"),
    ),
    Figure(
        "stunts.slowest",
        "slowest stunt (quick: 100 plans)",
        "s",
        _slowest_trick,
        higher=False,
        sized=True,
    ),
    Figure("stunts.success", "stunts meeting their targets", "", count("stunts", "success")),
    Figure(
        "aquarium.realtime",
        "aquarium 10 fishes, oracle",
        "x real time",
        at("aquarium", "realtime_factor"),
        baseline=at("aquarium", "physics_only_realtime_factor"),
        baseline_label="its physics alone, this run",
    ),
    Figure(
        "aquarium.frames",
        f"aquarium 10 fishes, frame = {AQUARIUM_FRAME_S:g} sim-s",
        "frames/s",
        _tank_frames,
        paper=PAPERS["tank"],
    ),
    Figure(
        "aquarium-60.realtime",
        "aquarium 60 fishes, oracle",
        "x real time",
        at("aquarium-60", "realtime_factor"),
        baseline=at("aquarium-60", "physics_only_realtime_factor"),
        baseline_label="its physics alone, this run",
    ),
    Figure(
        "aquarium-vision.realtime",
        "aquarium, one seeing predator",
        "x real time",
        at("aquarium-vision", "realtime_factor"),
        baseline=at("aquarium", "realtime_factor"),
        baseline_label="oracle tank, this run",
    ),
    Figure(
        "aquarium-skills.learned",
        "aquarium 10 fishes, learned skills",
        "x real time",
        at("aquarium-skills", "learned", "realtime_factor"),
        baseline=at("aquarium-skills", "built-in", "realtime_factor"),
        baseline_label="built-in skills' tank, this run",
    ),
    Figure(
        "jax.cpu",
        "JAX on CPU",
        "sim-s/s",
        _jax_on("cpu"),
        baseline=NUMBA,
        baseline_label="Numba kernel, this run",
    ),
    Figure(
        "jax.gpu",
        "JAX on a GPU",
        "sim-s/s",
        _jax_on("gpu"),
        baseline=NUMBA,
        baseline_label="Numba kernel (CPU), this run",
    ),
    Figure("jax.compile", "JAX compile", "s", at("jax", "jax", "compile_seconds"), higher=False),
    Figure(
        "jax.compile_cached",
        "JAX compile, cached (a later run)",
        "s",
        at("jax", "jax", "compile_seconds_cached"),
        higher=False,
    ),
    Figure(
        "san.search",
        "SAN search, walker",
        "sim-s/s",
        at("san", "simulated_seconds_per_second"),
        paper=PAPERS["san"],
    ),
    Figure(
        "ray.generation",
        "Ray (local), per generation",
        "s",
        at("ray", "ray_s_per_generation"),
        higher=False,
        baseline=at("ray", "in_process_s_per_generation"),
        baseline_label="in process, this run",
    ),
    Figure(
        "gym.native",
        "gym native vector env",
        "steps/s",
        at("gym", "native_env_steps_per_second"),
        baseline=at("gym", "sync_env_steps_per_second"),
        baseline_label="SyncVectorEnv, this run",
    ),
    Figure(
        "vision.retina",
        "retina, 2 eyes",
        "frames/s",
        at("vision", "retina_frames_per_second"),
    ),
    Figure("vision.loop", "pursuit loop", "frames/s", at("vision", "frames_per_second")),
    Figure("track.reached", "tracking: targets reached", "", at("track", "reached")),
    Figure(
        "track.wall",
        "tracking: wall",
        "s",
        at("track", "tracking_wall_s"),
        higher=False,
        sized=True,
    ),
    Figure(
        "render.skin",
        "video frame, display skin",
        "ms",
        at("render", "skin_ms_per_frame"),
        higher=False,
        baseline=at("render", "lattice_ms_per_frame"),
        baseline_label="raw lattice, this run",
    ),
)


def _short(command: str, width: int = 32) -> str:
    """A README command for the table's figure column: without ``zoetic``, cut at ``width``."""
    text = command.removeprefix("zoetic ")
    return text if len(text) <= width else text[: width - 1] + "…"


def readme_figures(results: dict) -> list[Figure]:
    """One figure per README command that ``bench readme`` timed: its CPU seconds beside the
    time the README states."""
    rows = at("readme", "commands")(results) or []
    return [
        Figure(
            f"readme.{row['command']}",
            f"README: {_short(row['command'])}",
            "s CPU",
            lambda _, row=row: row["cpu_s"],
            higher=False,
            baseline=lambda _, row=row: row["stated_s"],
            baseline_label="the README states",
            sized=True,
        )
        for row in rows
    ]
