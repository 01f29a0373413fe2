"""``zoetic view RUN_DIR``: the run in the browser (served locally, or one offline HTML file)."""

from __future__ import annotations

from pathlib import Path

import typer

from zoetic.cli.apps import app
from zoetic.cli.output import console


@app.command()
def view(
    run_dir: Path = typer.Argument(..., help="A run directory (it holds record.npz)."),
    html: Path = typer.Option(None, "--html", help="Write one self-contained HTML file instead."),
    port: int = typer.Option(8000, min=0, max=65535, help="Port on 127.0.0.1 (0: any free)."),
    fps: float = typer.Option(30.0, min=1.0, help="Frames per second kept of the run."),
    open_browser: bool = typer.Option(True, "--open/--no-open", help="Open a browser if any."),
) -> None:
    """Look at a run in 3D in the browser: scrub, play, orbit, follow the animal."""
    from zoetic.record import read_record
    from zoetic.viz.scene import scene_of
    from zoetic.viz.viewer import viewer_data
    from zoetic.web.page import page_html, write_html

    rec = read_record(run_dir)
    data = viewer_data(scene_of(rec, fps), rec)
    if html is not None:
        path = write_html(data, html)
        console.print(f"wrote {path} ({path.stat().st_size / 1024:.0f} KiB); open it in a browser")
        return
    from zoetic.web.server import serve

    serve(page_html(data), port, open_browser, console.print)
