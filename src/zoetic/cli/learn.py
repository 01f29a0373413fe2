"""``zoetic learn``, ``zoetic tasks``, ``zoetic demo`` and ``zoetic bench learn``."""

from __future__ import annotations

import shlex
from functools import partial
from pathlib import Path

import typer

from zoetic.cli.apps import app
from zoetic.cli.bench import bench_app, capped
from zoetic.cli.options import Animal, Force, Json, Quick, Seed, given, use_ray_address
from zoetic.cli.output import console, emit, interrupted, print_summary, progress_bar
from zoetic.learning.config import DEMO_BUDGET, demo_config
from zoetic.outdir import check_out_dir, prepare_out


@app.command()
def tasks() -> None:
    """List the built-in tasks, one line each: requirements, horizon, starts, description."""
    from zoetic.tasks import list_tasks, load_task

    for name in list_tasks():
        t = load_task(name)
        console.print(
            f"[bold]{name:16s}[/] {', '.join(t.requires) or '-':28s} {t.horizon:4.1f} s  "
            f"from {' and '.join(t.start_names()):17s} {t.description}"
        )


def learn_bar():
    """The learning bar: evaluations, best E, status and evaluations per second."""
    return progress_bar(
        "E {task.fields[best]}", "{task.fields[status]}", "{task.fields[rate]}/s", width=16
    )


def run_with_progress(run, label: str, every_s: float = 2.0) -> None:
    """Learn to the run's budget with a Rich progress bar; Ctrl-C leaves a resumable run."""
    budget = run.setup.config.budget
    with learn_bar() as bar:
        tid = bar.add_task(
            label, total=budget, completed=run.evaluations, best="-", status="", rate="-"
        )
        start_evals = run.evaluations

        def update(r) -> None:
            opt = r.setup.optimizer
            status = " ".join(f"{k} {v:.2g}" for k, v in opt.status().items())
            elapsed = max(bar.tasks[0].elapsed or 1e-9, 1e-9)
            bar.update(
                tid,
                completed=min(r.evaluations, budget),
                best=f"{opt.best_f:.4g}",
                status=status,
                rate=f"{(r.evaluations - start_evals) / elapsed:.0f}",
            )

        try:
            run.learn(progress=update, every_s=every_s)
        except KeyboardInterrupt:
            interrupted(
                f"saved {run.out} at {run.evaluations} of {budget} evaluations; continue with: "
                f"zoetic learn --resume {shlex.quote(str(run.out))}"
            )


# learn's options that a run stores in its config.toml: a resumed run keeps them
STORED = (
    "animal task optimizer seed controller nodes frequency interp popsize chains evaluator "
    "coupling fins start stop_generations stop_improvement"
).split()


@app.command()
def learn(
    ctx: typer.Context,
    animal: Animal = None,
    task: str = typer.Option("swim-straight", help="Task name (see `zoetic tasks`) or .toml file."),
    optimizer: str = typer.Option("cmaes", help="cmaes, anneal, simplex or gradient."),
    budget: int = typer.Option(3500, min=1, max=10_000_000, help="Evaluations to spend."),
    seed: Seed = 0,
    controller: str = typer.Option(
        "periodic", help="Representation: periodic (a gait that repeats), time or frequency."
    ),
    nodes: int = typer.Option(
        None, min=2, help="M, parameters per actuator (default 5 periodic, else the task's)."
    ),
    frequency: float = typer.Option(
        None, min=0.01, help="Periodic controller's base frequency, Hz (default: animal's wave)."
    ),
    interp: str = typer.Option("linear", help="Time-domain interpolation: linear or bspline."),
    popsize: int = typer.Option(None, min=2, help="CMA-ES population size (default 32)."),
    chains: int = typer.Option(1, min=1, help="Parallel annealing chains."),
    evaluator: str = typer.Option(
        "batch", help="batch (Numba threads), process (pool) or ray (actors on a Ray cluster)."
    ),
    ray_address: str = typer.Option(
        None,
        help="Ray cluster for --evaluator ray, e.g. 10.0.0.1:6379 (default: RAY_ADDRESS, "
        "else a local Ray).",
    ),
    coupling: str = typer.Option(
        "auto",
        help="auto (wave for a task that prefers neither side, else none), none, wave "
        "(right = left, later by the animal's wave lag) or antiphase (right = 1 - left).",
    ),
    fins: str = typer.Option(
        "auto", help="auto (learned for turns, else held level), held or free."
    ),
    start: str = typer.Option(
        "random", help="Where the search starts: random, or wave (the animal's own wave)."
    ),
    stop_generations: int = typer.Option(
        None, help="Stop when the best E improves by at most --stop-improvement in K generations."
    ),
    stop_improvement: float = typer.Option(
        None, help="That improvement, a fraction of |best E| (e.g. 0.001)."
    ),
    out: Path = typer.Option(
        None, help="Run directory, new or empty (default runs/<animal>-<task>)."
    ),
    resume: Path = typer.Option(
        None, help="Continue the run in this directory (a new --budget is taken)."
    ),
    force: Force = False,
    video: bool = typer.Option(True, help="Write video.mp4 of the best controller."),
    checkpoint_every: float = typer.Option(2.0, min=0.0, help="Seconds between checkpoints."),
) -> None:
    """Learn a controller for an animal and a task; writes a resumable run directory."""
    from zoetic.runs import finish_run
    from zoetic.viz.media import learning_media

    use_ray_address(ray_address)  # the run's config keeps only the evaluator's name
    if resume is not None:
        run = _resume(resume, ctx, budget)
    else:
        if animal is None:
            raise typer.BadParameter("give an ANIMAL (or --resume RUN_DIR)")
        config = _new_config(ctx)
        run = _create(config, out, force)
    cfg = run.setup.config
    run_with_progress(run, f"{cfg.animal} {cfg.optimizer}", checkpoint_every)
    summary = finish_run(run, partial(learning_media, video=video))
    _print_summary(summary)


def _new_config(ctx: typer.Context):
    """Return the LearnConfig of a new run: the stored options (``STORED``) and the budget as
    given ("random" start: the config's None)."""
    from zoetic.learning.run import LearnConfig

    options = {name: ctx.params[name] for name in STORED + ["budget"]}
    options["start"] = None if options["start"] == "random" else options["start"]
    return LearnConfig(**options)


def _resume(resume: Path, ctx: typer.Context, budget: int):
    """Open the run in ``resume`` where it stopped, with a new budget when --budget is given;
    refuse other stored settings given otherwise than stored (errors name the directory)."""
    from zoetic.errors import ZoeticError, naming
    from zoetic.learning.checks import run_dir_parts
    from zoetic.learning.run import Run

    if given(ctx, "out") or given(ctx, "force"):
        raise typer.BadParameter(f"a resumed run stays in {resume}; leave out --out and --force")
    try:
        stored = run_dir_parts(resume)[0]
        _check_same(resume, stored, ctx)
        run = Run.resume(resume, budget if given(ctx, "budget") else None)
    except ZoeticError as exc:
        raise naming(resume, exc) from None
    was, now = stored.budget, run.setup.config.budget
    change = f"; budget {was} -> {now} (--budget)" if now != was else f" of {now}"
    console.print(f"resuming {resume} at {run.evaluations} evaluations{change}")
    if run.evaluations >= now:
        console.print(f"the budget of {now} evaluations is spent; writing the results")
    return run


def _check_same(resume: Path, stored, ctx: typer.Context) -> None:
    """Refuse a stored setting given on the command line with another value than the run's."""
    from zoetic.errors import RunDirError

    for name in STORED:
        value, kept = ctx.params[name], getattr(stored, name)
        kept = "random" if name == "start" and kept is None else kept  # None: the default
        if given(ctx, name) and value != kept:
            flag = "ANIMAL" if name == "animal" else "--" + name.replace("_", "-")
            raise RunDirError(
                f"{flag} {value} differs from the run's {kept}: a resumed run keeps its "
                "settings (only --budget may change); start a new run with another --out"
            )


def _create(config, out: Path | None, force: bool):
    """Start a new run of ``config`` in ``out`` (default runs/<animal>-<task>), which must be
    empty (or, with ``force``, is emptied)."""
    from zoetic.bodies import load_animal
    from zoetic.learning.run import Run

    animal, task = config.animal, config.task
    out = out or Path("runs") / f"{Path(animal).stem}-{Path(task).stem}"
    out = prepare_out(out, force, f"zoetic learn --resume {shlex.quote(str(out))}")
    return Run.create(out, config, load_animal(animal))  # the run checks: learning.checks


def _print_summary(summary: dict) -> None:
    """Print a finished learning run's summary, one aligned ``key: value`` line each."""
    print_summary(summary, 14)


def _start_words(config) -> str:
    """How the demo's search starts, in words (``LearnConfig.start``)."""
    if config.start == "wave":
        return "starting from its own travelling wave"
    return "with random muscle signals"


def demo_banner(config) -> str:
    """What the demo is about to do, in words computed from its config and task file."""
    from zoetic.tasks import load_task

    task = load_task(config.task)
    n = len(task.starts)
    starts = f"from {n} starts ({', '.join(s.name or '?' for s in task.starts)})" if n > 1 else ""
    return (
        f"[bold]zoetic demo[/]: a {config.animal} {_start_words(config)} learns "
        f"{task.name} ({config.optimizer}): {config.budget} candidate controllers, each "
        f"simulated for {task.horizon:g} s {starts}".rstrip()
        + "."
    )


@app.command()
def demo(
    out: Path = typer.Option(Path("runs/demo"), help="Where to write the demo run."),
    budget: int = typer.Option(DEMO_BUDGET, min=16, max=10_000_000, help="Evaluations to spend."),
    seed: int = typer.Option(0),
    video: bool = typer.Option(True),
) -> None:
    """A shark learns to swim farther than its own wave (CMA-ES, 40 nodes per muscle)."""
    from zoetic.learning.run import Run
    from zoetic.runs import clear_demo, finish_run, mark_demo
    from zoetic.viz.media import learning_media

    check_out_dir(out)
    clear_demo(out)  # only what an earlier demo made; anything else stays
    before = {p.name for p in out.iterdir()} if out.is_dir() else set()
    config = demo_config(budget, seed)
    console.print(demo_banner(config))
    run = Run.create(out, config)
    try:
        run_with_progress(run, "shark learns to swim")
        summary = finish_run(run, partial(learning_media, video=video))
    finally:  # also when interrupted: the next demo may then clear what this one made
        mark_demo(out, before)
    _print_summary(summary)


@bench_app.command("learn")
def bench_learn_cmd(
    budget: int = typer.Option(3500, min=10),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """Annealing's wall time for the paper's budget, and how fast CMA-ES/gradient match it."""
    from zoetic.bench.learn import bench_learn

    emit(bench_learn(capped(quick, budget, 300), max_seconds=capped(quick, 60.0, 10.0)), json)


@bench_app.command("skills")
def bench_skills_cmd(
    animal: list[str] = typer.Option(None, help="Animals to learn (default: the whole zoo)."),
    budget: int = typer.Option(None, min=10, help="Evaluations per skill (default: learn's)."),
    seed: int = typer.Option(0),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """Learn each basic skill with defaults; print it beside the hand-made entry, and the time.
    --quick: the shark alone, 150 evaluations per skill."""
    from zoetic.bench.skills import bench_skills

    if quick:
        animal, budget = animal or ["shark"], capped(quick, budget or 150, 150)
    emit(bench_skills(animal or None, budget, seed), json)
