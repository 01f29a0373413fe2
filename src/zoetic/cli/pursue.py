"""``zoetic pursue``: a predator fish with active vision chases a reddish prey (seed 003, 3)."""

from __future__ import annotations

from pathlib import Path

import typer

from zoetic.cli.apps import app
from zoetic.cli.options import Force
from zoetic.cli.output import console
from zoetic.io import make_dir, write_json


@app.command()
def pursue(
    seconds: float = typer.Option(30.0, min=0.1, help="Simulated seconds (stops at a catch)."),
    seed: int = typer.Option(0, help="Seed of the prey's path, start and scenery."),
    out: Path = typer.Option(Path("runs/chase"), help="Output directory."),
    distractors: int = typer.Option(1, min=0, help="Yellowish distractor fish."),
    visibility: float = typer.Option(6.0, min=0.0, help="Water clarity: fog distance (m)."),
    fps: float = typer.Option(30.0, min=1.0, help="Vision frames per simulated second."),
    skills: str = typer.Option(
        "built-in",
        help="The predator's motor skills: built-in (the calibrated wave), learned (the "
        "repertoire shipped for the shark) or a learned repertoire's directory.",
    ),
    video: bool = typer.Option(True, help="Write video.mp4 (the slowest part)."),
    width: int = typer.Option(320, min=32, help="Width of the world view in the video (px)."),
    force: Force = False,
) -> None:
    """Chase a reddish prey by sight: saccades, vergence, stabilisation, and turns by the
    fish's turn motor controllers from its gaze angles.

    Writes video.mp4 (world view, gaze rays, both retinas), gaze.png (Fig. 7), frames.png
    (Fig. 8), summary.json and record.npz.
    """
    from zoetic.outdir import prepare_out
    from zoetic.perception.pursuit import make_chase, run_chase, summarize
    from zoetic.viz.gaze import chase_frames, plot_frames, plot_gaze
    from zoetic.viz.video import write_mp4

    out = make_dir(prepare_out(out, force))
    chase = make_chase(seed, distractors=distractors, visibility=visibility, skills=skills)
    with console.status("pursuing"):
        result = run_chase(chase, seconds, fps=fps, seed=seed)
    summary = summarize(result, chase.predator.gaze.spec) | {
        "seed": seed,
        "seconds": seconds,
        "skills": skills,
    }
    write_json(out / "summary.json", summary)
    from zoetic.cli.records import write_chase_record

    write_chase_record(out, chase, result, summary)
    plot_gaze(result.log, out / "gaze.png")
    plot_frames(result.log, out / "frames.png")
    if video:
        height = (width * 3 // 4) // 2 * 2
        frames = chase_frames(chase.world, chase.scenery, result, width, height)
        write_mp4(frames, out / "video.mp4", fps=fps)
    verdict = f"caught in {summary['time_to_catch_s']:.1f} s" if result.caught else "not caught"
    console.print(
        f"{verdict}; prey foveated {summary['foveated_fraction']:.0%} of "
        f"{summary['frames']} frames; distractor fixations "
        f"{summary['distractor_fixations']} -> {out}"
    )
