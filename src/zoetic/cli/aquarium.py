"""``zoetic aquarium``: a tank of artificial fishes living for a while, and what they did."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from zoetic.cli.apps import app
from zoetic.cli.bench import bench_app, capped
from zoetic.cli.options import Force, Json, Quick
from zoetic.cli.output import console, emit

Food = Annotated[
    int, typer.Option(help="Food particles drifting in the current [default: 1.5 a fish].")
]
"""How many food particles the tank holds."""

Obstacles = Annotated[
    int, typer.Option(help="Rocks and seaweed [default: 5 for 10 fishes, 5 sqrt(fishes / 10)].")
]
"""How many rocks and seaweed clumps the tank holds."""

Perception = Annotated[
    str,
    typer.Option(
        help="oracle (the world model) or vision (the first --seeing predators see with "
        "animat vision: rendered eyes, colour recognition, gaze; the rest use the oracle).",
    ),
]
"""How the fishes perceive the tank."""

Seeing = Annotated[
    str,
    typer.Option(help="With --perception vision: how many predators see (the first ones), or all."),
]
"""How many predators see with animat vision (``seeing_count``)."""

PredatorSkills = Annotated[
    Path,
    typer.Option(
        "--predator-skills",
        help="A learned repertoire's directory (zoetic repertoire "
        "train) the predator swims by instead of its species' motor skills.",
    ),
]
"""The learned repertoire the predator swims by."""

Skills = Annotated[
    str,
    typer.Option(
        "--skills",
        help="Every fish's motor skills instead of its species file's: "
        "learned (the repertoire shipped for its body, the species' default), built-in (the "
        "calibrated wave) or a learned repertoire's directory.",
    ),
]
"""Every fish's motor skills."""

Plants = Annotated[
    str,
    typer.Option(
        help="Seaweed as static plants (fixed cylinders) or dynamic (light strands that sway "
        "in the current and part around the fishes; about a fifth more CPU time).",
    ),
]
"""How the seaweed is simulated."""


@app.command()
def aquarium(
    fishes: int = typer.Option(10, help="Fishes in the tank, predators included."),
    predators: int = typer.Option(1, help="How many of them are predators (sharks)."),
    food: Food = None,
    obstacles: Obstacles = None,
    seconds: float = typer.Option(60.0, help="Simulated time (s)."),
    seed: int = typer.Option(0, help="Seed of the layout and of the fishes' wandering."),
    out: Path = typer.Option(Path("runs/tank"), help="Output directory."),
    perception: Perception = "oracle",
    seeing: Seeing = "1",
    prey: str = typer.Option("minnow", help="Prey species: a built-in name or a .toml file."),
    predator: str = typer.Option("shark", help="Predator species: a name or a .toml file."),
    predator_skills: PredatorSkills = None,
    skills: Skills = None,
    video: bool = typer.Option(True, help="Write video.mp4."),
    labels: bool = typer.Option(True, help="Label each fish with its intention in the video."),
    control_period: float = typer.Option(0.1, help="Brain period (s)."),
    plants: Plants = "static",
    force: Force = False,
) -> None:
    """Let a tank of fishes live: write events.csv, mind.png, summary.json, record.npz and
    video.mp4."""
    from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live
    from zoetic.outdir import prepare_out

    prepare_out(out, force)
    cfg = TankConfig(
        fishes=fishes,
        predators=predators,
        food=food,
        obstacles=obstacles,
        seconds=seconds,
        seed=seed,
        prey_species=prey,
        predator_species=predator,
        control_period=control_period,
        perception=perception,
        seeing=seeing_count(seeing, predators),
        record_period=min(0.05, control_period),
        predator_skills=None if predator_skills is None else str(predator_skills),
        skills=skills,
        plants=plants,
    )
    tank = build_tank(cfg)
    with console.status("the fishes live...") as status:
        life = live(tank, progress=lambda t: status.update(f"t = {t:.1f} s"))
    _write_outputs(out, cfg, tank, life, video, labels)


def _write_outputs(out: Path, cfg, tank, life, video: bool, labels: bool) -> None:
    """Write the tank's life into ``out``: events.csv, record.npz, mind.png, video.mp4 (with
    ``video``; labelled with ``labels``) and summary.json, then say what the fishes did."""
    from zoetic.behavior.aquarium.events import events_csv
    from zoetic.behavior.aquarium.tank import summarize
    from zoetic.cli.records import write_aquarium_record
    from zoetic.io import atomic_write_bytes, make_dir, write_json
    from zoetic.record import read_record
    from zoetic.viz.media import mind_media

    make_dir(out)
    atomic_write_bytes(out / "events.csv", events_csv(life.events).encode())
    summary = summarize(tank, life)
    record = write_aquarium_record(out, tank, life, summary)
    mind_media(read_record(record), out)
    if video:
        _write_video(out / "video.mp4", cfg, tank, life, labels)
    write_json(out / "summary.json", summary)
    _report(summary, out, video)


def seeing_count(text: str, predators: int) -> int:
    """Return the number of seeing predators ``--seeing`` asks for: a whole number, or all of
    the ``predators``; raise ZoeticError (exit 2) for anything else."""
    from zoetic.errors import ZoeticError

    word = text.strip().lower()
    if word == "all":
        return max(predators, 1)
    if not word.isdigit() or int(word) < 1:
        raise ZoeticError(f"--seeing: a whole number of predators from 1, or all; got {text!r}")
    return int(word)


def _write_video(path: Path, cfg, tank, life, labels: bool) -> None:
    """Render the tank's life (fishes, rocks and seaweed, food; each fish's intention as a
    label when ``labels``) into an MP4 at ``path``."""
    from zoetic.behavior.aquarium.tank import frame_labels
    from zoetic.viz.aquarium import write_tank_video

    names = [f.name for f in tank.fishes]
    centers = [tank.center[k] for k, nm in enumerate(tank.static_names) if nm != "wall"]
    with console.status("rendering the video..."):
        write_tank_video(
            path,
            fps=1.0 / cfg.record_period,
            bodies=[f.body for f in tank.fishes],
            positions=life.positions,
            times=life.times,
            colors=[f.species.color for f in tank.fishes],
            looks=[f.species.name for f in tank.fishes],
            statics=(tank.kind, tank.center, tank.size, tank.static_names),
            focus=next((k for k, f in enumerate(tank.fishes) if f.species.predator), 0),
            obstacles=centers,
            food=life.food,
            eaten=life.eaten,
            labels=frame_labels(life, names) if labels else None,
            half_size=cfg.size(),
            plants=life.plants,
        )


def _report(summary: dict, out: Path, video: bool) -> None:
    """Print what the tank's fishes did and what was written."""
    ev = summary["events"]
    console.print(
        f"{summary['seconds']:.1f} s simulated in {summary['wall_seconds']:.1f} s "
        f"(x{summary['realtime_factor']:.1f} real time); events: "
        + ", ".join(f"{k} {v}" for k, v in ev.items())
        + f"; food eaten {100 * summary['food_eaten_fraction']:.0f} %; survivors "
        f"{summary['survivors']}/{summary['fishes']}; deepest into a rock "
        f"{summary['deepest_into_obstacle_m']:.3f} m, into a fish "
        f"{summary['deepest_into_fish_m']:.3f} m"
    )
    console.print(
        f"wrote {out}/events.csv, mind.png, summary.json, record.npz" + (", video.mp4" * video)
    )


@bench_app.command("aquarium")
def bench_aquarium_cmd(
    fishes: int = typer.Option(10),
    food: int = typer.Option(None, help="Food particles [default: 1.5 a fish]."),
    obstacles: int = typer.Option(None, help="Rocks and seaweed [default: 5 sqrt(fishes / 10)]."),
    seconds: float = typer.Option(60.0, min=0.5),
    seed: int = typer.Option(0),
    predators: int = typer.Option(1, help="How many of the fishes are predators (sharks)."),
    perception: Perception = "oracle",
    seeing: Seeing = "1",
    predator_skills: PredatorSkills = None,
    skills: str = typer.Option(
        None,
        "--skills",
        help="Every fish's motor skills: built-in, learned, a repertoire's "
        "directory, or both (the built-in and the learned tank side by side); default the "
        "species files'.",
    ),
    plants: str = typer.Option("static", help="Seaweed as static cylinders or dynamic plants."),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """Realtime factor of a tank (oracle perception, or animat vision for --seeing
    predators), against its physics alone."""
    from zoetic.bench.aquarium import bench_aquarium

    pred = None if predator_skills is None else str(predator_skills)
    seconds = capped(quick, seconds, 5.0)
    emit(
        bench_aquarium(
            fishes,
            food,
            obstacles,
            seconds,
            seed,
            perception,
            pred,
            skills,
            plants,
            predators,
            seeing_count(seeing, predators),
        ),
        json,
    )
