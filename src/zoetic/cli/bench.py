"""``zoetic bench ...``: benchmarks that print side-by-side ratios (never assertions)."""

from __future__ import annotations

import json

import typer

from zoetic.cli import app

bench_app = typer.Typer(help="Benchmarks; figures are ratios measured side by side.")
app.add_typer(bench_app, name="bench")


def _emit(result: dict, as_json: bool) -> None:
    if as_json:
        print(json.dumps(result))
    else:
        for key, value in result.items():
            print(f"{key:40s} {value}")


@bench_app.command("gym")
def bench_gym_cmd(
    env_id: str = typer.Option("zoetic/SharkSwim-v0", "--env", help="A zoetic environment id."),
    num_envs: int = typer.Option(64, min=1, help="Environments stepped together."),
    steps: int = typer.Option(100, min=1, help="Vector steps timed."),
    json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Env steps per second: the native vector env against SyncVectorEnv, same actions."""
    from zoetic.gym.bench import bench_gym

    _emit(bench_gym(env_id, num_envs, steps), json)


@bench_app.command("vision")
def bench_vision_cmd(
    frames: int = typer.Option(150, min=10, help="Vision frames timed."),
    json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Animat vision: retina frames/s (2 eyes x 4 levels) and the whole pursuit loop's."""
    from zoetic.perception.bench import bench_vision

    _emit(bench_vision(frames), json)
