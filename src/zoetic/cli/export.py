"""``zoetic export RUN_DIR --gltf out.glb``: a run as an animated glTF 2.0 binary."""

from __future__ import annotations

from pathlib import Path

import typer

from zoetic.cli.apps import app
from zoetic.cli.output import console


@app.command()
def export(
    run_dir: Path = typer.Argument(..., help="A run directory (it holds record.npz)."),
    gltf: Path = typer.Option(..., "--gltf", help="The .glb file to write."),
    fps: float = typer.Option(30.0, min=1.0, help="Frames per second of the animation."),
) -> None:
    """Write the run as an animated glTF 2.0 binary (.glb) for Blender, three.js, ..."""
    from zoetic.viz.gltf import write_glb
    from zoetic.viz.scene import load_scene

    scene = load_scene(run_dir, fps)
    path = write_glb(scene, gltf)
    size = path.stat().st_size
    console.print(
        f"wrote {path} ({size / 1024:.0f} KiB): {len(scene.movers)} animal(s), "
        f"{len(scene.objects)} object(s), "
        f"{len(scene.times)} frames at {fps:g} fps over {scene.duration:.2f} s"
    )
