"""``zoetic track`` (greedy target tracking) and ``zoetic macro`` (planned macro controllers)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from zoetic.cli.apps import app
from zoetic.cli.options import (
    Animal,
    Evaluator,
    Force,
    Fps,
    Memory,
    Method,
    RayAddress,
    RunDir,
    Seed,
    use_ray_address,
)
from zoetic.cli.output import console, progress_bar
from zoetic.io import make_dir
from zoetic.outdir import prepare_out

PLANE = (
    "Points are x,z (m) in the horizontal plane: the animal starts at the origin facing +x "
    "and +z is its left."
)
SPACE = (
    "Points are x,z (m, at the start depth) or x,y,z with y m above the start depth "
    "(negative: deeper): the animal starts at the origin facing +x and +z is its left; a "
    "target counts as reached when the centre of mass comes within the radius of it in 3D."
)


def track_bar(unit: str):
    """The tracking and planning bar: count in ``unit`` and an info column."""
    return progress_bar(
        "{task.fields[info]}", count="{task.completed:>6.0f}/{task.total:.0f} " + unit
    )


def _setup(animal: str, memory: Path):
    """Return the body and its repertoire (clear errors for a missing or mismatched one)."""
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.bodies import load_animal

    body = load_animal(animal)
    return body, Repertoire.load(memory, body)


def _buoys(points_xz: np.ndarray, depth: float) -> np.ndarray:
    """Return (M, 3) world points at the animal's depth for (M, 2) plane points."""
    pts = np.asarray(points_xz, float).reshape(-1, 2)
    return np.column_stack([pts[:, 0], np.full(len(pts), depth), pts[:, 1]])


def _rings(obstacles: np.ndarray, depth: float, per: int = 16) -> np.ndarray:
    """Return buoys spaced around each obstacle disc's rim, (O * per, 3)."""
    a = np.linspace(0, 2 * np.pi, per, endpoint=False)
    rims = [np.column_stack([x + r * np.cos(a), z + r * np.sin(a)]) for x, z, r in obstacles]
    return _buoys(np.concatenate(rims), depth) if rims else np.zeros((0, 3))


@app.command()
def track(
    animal: Animal,
    memory: Memory,
    targets: str = typer.Option(..., help=f"Targets 'x,z;x,y,z;...' visited in order. {SPACE}"),
    out: RunDir = Path("runs/track"),
    interval: float = typer.Option(1.0, min=0.05, help="Re-evaluation interval (s)."),
    radius: float = typer.Option(None, help="Reaching radius (m); default half a body length."),
    time_limit: float = typer.Option(
        120.0, min=0.1, max=3600.0, help="Give up after this many seconds."
    ),
    turn_radius: float = typer.Option(
        None,
        help="Metres per radian of bearing added to the distance in the gain (default 1.5 "
        "body lengths); 0 for the distance alone.",
    ),
    video: bool = typer.Option(True, help="Write video.mp4 with the targets as buoys."),
    fps: Fps = 30,
    force: Force = False,
) -> None:
    """Track targets greedily with a repertoire (Fig. 5, Plate 4); writes path.png and video."""
    from zoetic.behavior.targets import parse_targets
    from zoetic.behavior.tracking import TrackConfig

    pts = parse_targets(targets)
    prepare_out(out, force)
    body, rep = _setup(animal, memory)
    config = TrackConfig(
        interval=interval, radius=radius, time_limit=time_limit, turn_radius=turn_radius
    )
    result = _run_track(body, rep, pts, config)
    make_dir(out)
    reached = _write_track(out, body, result, pts, memory)
    if video:
        from zoetic.viz.render3d import render_video

        render_video(
            body,
            result.positions,
            result.times,
            body.medium,
            out / "video.mp4",
            fps=fps,
            markers=result.targets,
            marker_colors=(220, 40, 30),
        )
    console.print(
        f"reached {reached}/{len(pts)} targets (in 3D, within {result.radius:.2f} m) in "
        f"{result.sim_time:.1f} s simulated, {result.wall:.2f} s wall: "
        f"[bold]{result.realtime_factor:.0f}x real time[/] ({len(result.names)} controllers, "
        f"{len(result.evaluations)} re-evaluations of {len(rep.names)} entries and their "
        "fin-righting variants in one batch each)"
    )
    console.print(motion_line(result.motion))
    _report_files(out, video)


def motion_line(m: dict) -> str:
    """Return a locomotion summary's depth, attitude and turn figures in words."""
    lo, hi = m["depth_span_m"]
    return (
        f"depth: {m['depth_change_m']:+.2f} m at the end (between {lo:+.2f} and {hi:+.2f} m "
        f"of the start depth); worst roll {m['worst_roll_deg']:.0f} deg, worst pitch "
        f"{m['worst_pitch_deg']:.0f} deg; net turn {m['turn_deg']:+.0f} deg (left +)"
    )


def _run_track(body, rep, pts: np.ndarray, config):
    """Track the targets ``pts`` (M, 3) under a progress bar; return the tracking result."""
    from zoetic.behavior.tracking import track as run_track

    with track_bar("s") as bar:
        tid = bar.add_task(f"{body.name} tracks", total=config.time_limit, info="")

        def update(t: float, reached: int) -> None:
            done = min(t, config.time_limit)
            bar.update(tid, completed=done, info=f"targets {reached}/{len(pts)}")

        result = run_track(body, rep, pts, config, progress=update)
        bar.update(tid, total=result.sim_time, completed=result.sim_time)
    return result


def _write_track(out: Path, body, result, pts: np.ndarray, memory: Path) -> int:
    """Write a tracking run's controller, summary, record and path plot; return how many
    targets it reached."""
    from zoetic.behavior.tracking import replay
    from zoetic.cli.records import figures, write_sequence_record
    from zoetic.control import save_controller
    from zoetic.io import write_json
    from zoetic.viz.tracking import plot_plan

    check = replay(body, result)
    drift = float(np.nanmax(np.abs(check.positions[0] - result.positions)))
    summary = result.summary() | {
        "animal": body.name,
        "memory": str(memory),
        "targets_xyz": pts.tolist(),
        "plan": [
            {"entry": n, "start_s": round(float(s), 3)}
            for n, s in zip(result.names, result.starts, strict=True)
        ],
        "replay_drift_m": drift,
    }
    save_controller(result.sequence, out / "controller.json")
    write_json(out / "summary.json", summary)
    reached = int(np.isfinite(result.reached).sum())
    write_sequence_record(
        out,
        "track",
        body,
        result.times,
        result.positions,
        result.sequence,
        _target_things(result.targets),
        {"targets_reached": f"{reached}/{len(pts)}"} | figures(result.motion),
    )
    plot_plan(
        [result.com],
        ["path"],
        out / "path.png",
        result.targets,
        np.zeros((0, 3)),
        [result.start_indices],
        title=f"{body.name} tracking: {reached}/{len(pts)} targets reached in 3D "
        f"(white: a new controller starts)",
        band=0.5,
    )
    return reached


def _target_things(world: np.ndarray) -> list:
    """Return the record's target markers at their world points (M, 3)."""
    import dataclasses

    from zoetic.cli.records import targets

    return [
        dataclasses.replace(targets(p[[0, 2]], float(p[1]))[0], name=f"target {k + 1}")
        for k, p in enumerate(np.asarray(world, float))
    ]


# plans a macro search judges by default: a righted plan simulates each 1 s window's
# fin-righting variants where its planned entry drifts, about 6-10x the cost of a plain plan
RIGHTED_BUDGET = 300
PLAIN_BUDGET = 2000


@app.command()
def macro(
    animal: Animal,
    memory: Memory,
    goal: str = typer.Option(..., help=f"Goal 'x,z'. {PLANE}"),
    obstacle: list[str] = typer.Option(
        [], help="Obstacle disc 'x,z,r' to keep out of (repeat for more)."
    ),
    method: Method = "ga",
    budget: int | None = typer.Option(
        None,
        min=1,
        max=10_000_000,
        help=f"Plans (simulations) to evaluate [default: {RIGHTED_BUDGET} righted, "
        f"{PLAIN_BUDGET} with --no-righting, about the same time].",
    ),
    seed: Seed = 0,
    segments: int = typer.Option(6, min=1, help="Repertoire entries in a plan."),
    horizon: float = typer.Option(
        60.0, min=0.1, max=3600.0, help="Seconds the plan is judged over."
    ),
    out: RunDir = Path("runs/macro"),
    video: bool = typer.Option(True, help="Write video.mp4 (goal and obstacle rims as buoys)."),
    fps: Fps = 30,
    evaluator: Evaluator = "batch",
    ray_address: RayAddress = None,
    righting: bool = typer.Option(
        True,
        help="Search and play plans with the righting reflex of `zoetic sequence` (each 1 s "
        "window the planned entry or a fin-righting variant), so plans are judged as the fish "
        "swims them; --no-righting: as planned, durations not rounded to whole windows.",
    ),
    force: Force = False,
) -> None:
    """Search for a macro controller (selection, order, durations of entries) to reach a goal,
    upright and at depth; a fish plays and is judged with its righting reflex."""
    use_ray_address(ray_address)
    from zoetic.behavior.macro import MacroProblem, ReachTask
    from zoetic.behavior.tracking import TrackConfig
    from zoetic.control import save_controller
    from zoetic.control.measure import locomotion
    from zoetic.io import write_json

    g, obs = _goal_and_obstacles(goal, obstacle)
    prepare_out(out, force)
    body, rep = _setup(animal, memory)
    task = ReachTask(tuple(g), tuple(map(tuple, obs)), horizon)
    config = TrackConfig() if righting else None
    problem = MacroProblem(body, rep, task, segments=segments, righting=config)
    budget = budget or (RIGHTED_BUDGET if righting else PLAIN_BUDGET)
    result = _search_plan(problem, body.name, method, budget, seed, evaluator)
    make_dir(out)
    summary = result.summary() | {
        "animal": body.name,
        "memory": str(memory),
        "goal_xz": g.tolist(),
        "obstacles_xzr": obs.tolist(),
        "horizon_s": horizon,
        "seed": seed,
        "history": [[n, round(f, 5)] for n, f in result.history],
    }
    traj, sequence, righted = _play_plan(body, problem, result)
    save_controller(sequence, out / "controller.json")
    motion = locomotion(body, traj.positions[0], traj.times)
    drift = _replay_drift(body, sequence, traj.times, traj.positions[0])
    summary |= motion | {"righting": righted, "replay_drift_m": drift}
    write_json(out / "summary.json", summary)
    depth = float(traj.com(body)[0][0, 1])
    _write_plan_record(out, body, traj, sequence, g, obs, depth, summary)
    _draw_plan(out, body, traj, result, sequence.starts(), righted, g, obs, video, fps)
    _report_plan(method, result.summary(), out, video)
    if righted:
        console.print(
            f"righting reflex: a righting variant played in {righted['windows_righted']} of "
            f"{righted['windows']} windows (searched and played so)"
        )
    else:
        console.print("righting reflex: off (--no-righting or a finless animal)")
    console.print(motion_line(motion))


def _play_plan(body, problem, result):
    """Return the found plan as played (a trajectory recorded every 4 steps), the controller
    that plays it, and what the fins' righting reflex did (empty when off or finless): a
    plan is played as it was judged in the search, with the reflex where the problem has it
    (the recorded controller then holds the variants the reflex chose)."""
    if problem.righting is None:
        traj = problem.rollout(result.entries, result.durations, record_every=4)
        return traj, result.sequence, {}
    played = problem.righted(result.entries[None], result.durations[None])
    r = played.result(0)
    s = r.summary()
    return played.trajectory(), r.sequence, {k: s[k] for k in ("windows", "windows_righted")}


def _replay_drift(body, sequence, times: np.ndarray, positions: np.ndarray) -> float:
    """Return how far (m, the worst node coordinate) the controller, played from rest in a
    World, strays from the path it was recorded with (``positions`` (R, N, 3) at ``times``)."""
    from zoetic.control.rollout import rollout
    from zoetic.physics.world import World

    every = int(round((times[1] - times[0]) / body.dt))
    steps = int(round(times[-1] / body.dt))
    seconds = steps * body.dt
    table = sequence.table(steps, body.dt)[None]
    again = rollout(World([body]), table, seconds, seconds, record_every=every).positions[0][0]
    n = min(len(again), len(positions))
    return float(np.nanmax(np.abs(again[:n] - positions[:n])))


def _goal_and_obstacles(goal: str, obstacle: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Parse --goal 'x,z' and each --obstacle 'x,z,r' (radii must be positive)."""
    from zoetic.behavior.targets import TrackingError, parse_points

    g = parse_points(goal, 2, "--goal")[0]
    obs = np.concatenate([parse_points(o, 3, "--obstacle") for o in obstacle] or [np.zeros((0, 3))])
    if np.any(obs[:, 2] <= 0):
        raise TrackingError(f"--obstacle: radii must be positive, got {obs[:, 2].tolist()}")
    return g, obs


def _search_plan(problem, name: str, method: str, budget: int, seed: int, evaluator: str):
    """Search the macro problem under a progress bar; return the search's result."""
    from zoetic.behavior.macro import search

    with track_bar("plans") as bar:
        tid = bar.add_task(f"{name} {method}", total=budget, info="")

        def update(opt) -> None:
            st = " ".join(f"{k} {v:.2g}" for k, v in opt.status().items())
            bar.update(tid, completed=min(opt.evaluations, budget), info=f"E {opt.best_f:.3f} {st}")

        return search(problem, method, budget, seed, progress=update, evaluator=evaluator)


def _draw_plan(
    out: Path,
    body,
    traj,
    result,
    starts: np.ndarray,
    righted: dict,
    goal: np.ndarray,
    obstacles: np.ndarray,
    video: bool,
    fps: int,
) -> None:
    """Write a macro run's path.png, white dots at ``starts`` (s, each played item's), its
    title the played path's figures (``righted``: what the reflex did, empty when off), and
    video.mp4 (goal and obstacle rims as buoys)."""
    from zoetic.viz.tracking import plot_plan

    com = traj.com(body)[0]
    depth = float(com[0, 1])
    idx = np.searchsorted(traj.times, starts[starts < result.horizon] - 1e-9)
    s, method = result.summary(), result.method
    title = (
        f"{body.name} macro controller ({method}{', righting' if righted else ''}): "
        f"final distance {s['final_m']:.2f} m, {s['inside_obstacle_s']:.1f} s in obstacles, "
        f"worst roll {s['worst_roll_deg']:.0f} deg"
    )
    plot_plan(
        [com], [f"{method} plan"], out / "path.png", goal, obstacles, [idx], title=title, band=0.5
    )
    if video:
        from zoetic.viz.render3d import render_video

        rims = _rings(obstacles, depth)
        colors = [(220, 40, 30)] + [(240, 200, 40)] * len(rims)
        render_video(
            body,
            traj.positions[0],
            traj.times,
            body.medium,
            out / "video.mp4",
            fps=fps,
            markers=np.vstack([_buoys(goal, depth), rims]),
            marker_colors=colors,
        )


def _write_plan_record(
    out: Path, body, traj, sequence, goal, obstacles, depth: float, summary: dict
) -> None:
    """Write a macro run's record: the planned run, its goal and obstacle discs, figures."""
    from zoetic.cli.records import figures, obstacle_discs, targets, write_sequence_record

    things = targets(goal, depth, "goal") + obstacle_discs(obstacles, depth)
    write_sequence_record(
        out, "macro", body, traj.times, traj.positions[0], sequence, things, figures(summary)
    )


def _report_plan(method: str, s: dict, out: Path, video: bool) -> None:
    """Print what a macro controller achieved and what was written."""
    console.print(
        f"{method}: E = {s['cost']:.3f}, final distance {s['final_m']:.2f} m, closest "
        f"{s['closest_m']:.2f} m, {s['inside_obstacle_s']:.1f} s in obstacles, reached "
        f"{'at ' + str(s['reached_s']) + ' s' if s['reached_s'] is not None else 'never'}"
    )
    played = [f"{p['entry']} {p['duration_s']:.1f} s" for p in s["plan"] if p["played"]]
    console.print("plan: " + ", ".join(played))
    _report_files(out, video)


def _report_files(out: Path, video: bool) -> None:
    """Print what a tracking or macro run wrote: its controller, summary, record and path."""
    console.print(
        f"wrote {out}/ (controller.json, summary.json, record.npz, path.png"
        f"{', video.mp4' if video else ''})"
    )
