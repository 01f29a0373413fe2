"""What commands say before a long run: the demo's words come from its config, the stunt search
says its expected time early."""

from __future__ import annotations

import io
import time

from rich.console import Console

from zoetic.cli.learn import demo_banner
from zoetic.cli.output import Countdown, duration_words
from zoetic.learning.run import LearnConfig
from zoetic.tasks import load_task


def test_the_demo_banner_states_its_tasks_horizon_and_starts() -> None:
    config = LearnConfig(animal="shark", task="swim-straight", optimizer="cmaes", budget=8000)
    task = load_task("swim-straight")
    said = demo_banner(config)
    assert f"8000 candidate controllers, each simulated for {task.horizon:g} s" in said
    names = ", ".join(s.name for s in task.starts)
    assert len(task.starts) > 1 and f"from {len(task.starts)} starts ({names})" in said
    assert "random muscle signals" in said
    warm = demo_banner(LearnConfig(task="swim-straight", start="wave"))
    assert "starting from its own travelling wave" in warm and "random" not in warm


def test_the_demo_banner_follows_another_task() -> None:
    config = LearnConfig(animal="snake", task="turn-left", optimizer="anneal", budget=99)
    task = load_task("turn-left")
    said = demo_banner(config)
    assert "a snake" in said and "turn-left (anneal)" in said and "99 candidate" in said
    assert f"simulated for {task.horizon:g} s" in said
    assert ("starts" in said) == (len(task.starts) > 1)


def test_the_countdown_says_the_time_left_once_from_the_rate_after_the_first_step(
    monkeypatch,
) -> None:
    clock = iter([100.0, 100.5, 104.0, 200.0])  # step 1 (compiles), too soon, 4 s later, later
    monkeypatch.setattr(time, "perf_counter", lambda: next(clock))
    out = io.StringIO()
    console = Console(file=out, width=200)
    countdown = Countdown(1000, "plans")
    for done in (16, 32, 96, 112):
        countdown(done, console)
    # 80 plans in 4 s: 50 ms a plan, 904 left: 45 s
    assert out.getvalue().strip() == (
        "expected: about 45 s more for 904 plans (50 ms each on this machine)"
    )


def test_durations_read_as_people_say_them() -> None:
    assert [duration_words(s) for s in (0.2, 40, 420, 5400)] == ["1 s", "40 s", "7 min", "1.5 h"]
