"""Every kind of run in the viewer, in headless Chromium: the page draws the run's bodies and
what its kind adds (targets, obstacles, food and rocks, a ball and a bar, gaze rays, spray,
intention labels), and the plots beside the view (activations, mind, E history).

"Drawn" is read back from the WebGL canvas (``toDataURL``): the pixels that change when one
kind of thing is hidden (``window.zoetic.setLayer``) are the pixels it covered."""

from __future__ import annotations

import base64
import contextlib
from io import BytesIO
from pathlib import Path

import numpy as np
import pytest

from conftest import write_short_task
from test_web import viewer_page
from zoetic.cli import main
from zoetic.record import read_record

STUNT = """name = "drop-in"
requires = ["surface"]
horizon = 0.6
record_hz = 20.0
[start]
depth = -0.4                  # above the water: it falls in and splashes
speed = 1.0
[trick]
segments = 2
durations = [0.1, 0.5]
[[objects]]
kind = "ball"
name = "beach-ball"
radius = 0.25
mass = 0.3
position = [1.2, 0.5, 0.0]
[[objects]]
kind = "cylinder"
name = "bar"
center = [1.2, 0.49, 0.6]
radius = 0.03
length = 1.0
axis = "z"
[[terms]]
kind = "apex_above_surface"
weight = -1.0
"""


def _pixels(page) -> np.ndarray:
    """Return the 3D view's own pixels (H, W, 3), read from its WebGL canvas."""
    from PIL import Image

    url = page.evaluate("document.querySelector('#zoetic > canvas').toDataURL('image/png')")
    png = base64.b64decode(url.split(",", 1)[1])
    return np.asarray(Image.open(BytesIO(png)).convert("RGB"), float)


def _covered(page, layer: str) -> np.ndarray:
    """Return the mask (H, W) of the pixels that ``layer`` covers at the time shown: those
    that change when it is hidden (it is shown again afterwards)."""
    shown = _pixels(page)
    assert page.evaluate(f"window.zoetic.setLayer('{layer}', false)") > 0, f"no {layer} layer"
    hidden = _pixels(page)
    page.evaluate(f"window.zoetic.setLayer('{layer}', true)")
    return np.abs(shown - hidden).max(axis=2) > 12


@contextlib.contextmanager
def _open(run: Path, tmp_path: Path, t: float, fps: int = 20):
    """Write the run's page and its .glb with the CLI; open the page, check that three.js
    reads the .glb, and pause at time ``t`` (s)."""
    html = tmp_path / f"{run.name}.html"
    assert main(["view", str(run), "--html", str(html), "--fps", str(fps)]) == 0
    glb = tmp_path / f"{run.name}.glb"
    assert main(["export", str(run), "--gltf", str(glb), "--fps", str(fps)]) == 0
    with viewer_page(html) as (page, _):
        # the exported .glb, read by three.js's GLTFLoader: every body and object, animated
        b64 = base64.b64encode(glb.read_bytes()).decode()
        info = page.evaluate("b => window.zoetic.inspectGlb(b)", b64)
        rec = read_record(run)
        links = sum(len(c.links) for c in rec.creatures)
        assert info["meshes"] >= len(rec.animals) + links + len(rec.objects), info
        assert info["skinned"] == len(rec.animals) and info["animations"] == 1, info
        page.evaluate(f"window.zoetic.pause(); window.zoetic.setTime({t})")
        yield page


def _body_drawn(page, k: int = 0, share: float = 0.004) -> None:
    """Animal ``k``'s body covers at least ``share`` of the view, around its centre."""
    mask = _covered(page, "animals")
    assert mask.mean() > share, f"the bodies cover {100 * mask.mean():.2f}% of the view"
    ys, xs = np.nonzero(mask)
    c = page.evaluate(f"window.zoetic.project({k})")
    dpr = mask.shape[1] / page.evaluate("document.querySelector('#zoetic > canvas').clientWidth")
    x, y = c["x"] * dpr, c["y"] * dpr
    pad = 0.05 * mask.shape[1]
    assert xs.min() - pad <= x <= xs.max() + pad and ys.min() - pad <= y <= ys.max() + pad, (
        f"the body's pixels {xs.min()}..{xs.max()} x {ys.min()}..{ys.max()} miss its centre "
        f"({x:.0f}, {y:.0f})"
    )


def _panel(page, name: str) -> dict:
    """Return what side panel ``name`` shows, after checking that its canvas is drawn."""
    info = page.evaluate("window.zoetic.panels()")
    assert name in info, info
    shot = page.locator(f"#{name} canvas").first.screenshot()
    from PIL import Image

    img = np.asarray(Image.open(BytesIO(shot)).convert("RGB"), float)
    assert img.std() > 10, f"the {name} chart is blank"
    return info[name]


def _activations(page, actuators: int) -> None:
    info = _panel(page, "activations")
    assert info["actuators"] == actuators and info["frames"] == page.evaluate(
        "window.zoetic.frames"
    ), info


# ---------------------------------------------------------------- one tiny run of each kind


@pytest.fixture(scope="module")
def memory(tmp_path_factory) -> Path:
    """The shark's hand-made repertoire (track, macro, sequence)."""
    from zoetic.behavior.handmade import handmade_repertoire
    from zoetic.bodies import load_animal

    path = tmp_path_factory.mktemp("memory")
    handmade_repertoire(load_animal("shark")).save(path)
    return path


def _run(tmp_path: Path, name: str, args: list[str]) -> Path:
    out = tmp_path / name
    assert main([*args, "--out", str(out)]) == 0
    return out


def test_a_simulation_draws_its_body_and_activations(tmp_path):
    run = _run(tmp_path, "sim", ["simulate", "shark", "--seconds", "1", "--no-video"])
    with _open(run, tmp_path, 0.5) as page:
        _body_drawn(page)
        _activations(page, len(read_record(run).animals[0].actuators))


def test_a_learning_run_draws_its_best_and_its_E_history(tmp_path):
    task = write_short_task(tmp_path, horizon=0.5, nodes=4)
    args = ["learn", "shark", "--task", str(task), "--budget", "8", "--popsize", "4"]
    run = _run(tmp_path, "learn", [*args, "--no-video"])
    rec = read_record(run)
    assert len(rec.history["E"]) == 8 == len(rec.history["best_E"])
    assert np.all(np.diff(rec.history["best_E"]) <= 0)  # the best so far only improves
    assert rec.history["best_E"][-1] == pytest.approx(rec.numbers["best_E"], abs=1e-3)
    with _open(run, tmp_path, 0.25) as page:
        _body_drawn(page)
        info = _panel(page, "history")
        assert info["evaluations"] == 8 and info["best"] == pytest.approx(
            float(rec.history["best_E"][-1]), abs=1e-3
        )
        _activations(page, len(rec.animals[0].actuators))


@pytest.mark.parametrize("kind", ["track", "macro", "sequence"])
def test_repertoire_runs_draw_the_body_and_their_targets_and_obstacles(kind, memory, tmp_path):
    shark = ["shark", "--memory", str(memory)]
    args = {
        "track": [*shark, "--targets", "0.5,0.2", "--time-limit", "1.0"],
        "macro": [*shark, "--goal", "1.0,0.5", "--obstacle", "0.5,0.2,0.2", "--horizon", "1.0"],
        "sequence": [*shark, "--entries", "go-straight:0.5,sharp-turn-left:0.5"],
    }[kind]
    if kind == "macro":
        args += ["--segments", "2", "--budget", "4"]
    run = _run(tmp_path, kind, [kind, *args, "--no-video"])
    with _open(run, tmp_path, 0.2) as page:
        _body_drawn(page)
        _activations(page, len(read_record(run).animals[0].actuators))
        if kind != "sequence":  # the target; the goal and the obstacle disc
            assert _covered(page, "objects").mean() > 0.0005


@pytest.mark.slow
def test_an_aquarium_draws_fishes_food_rocks_intentions_and_minds(tmp_path):
    args = ["--fishes", "2", "--food", "2", "--obstacles", "1", "--seconds", "0.5"]
    run = _run(tmp_path, "tank", ["aquarium", *args, "--no-video"])
    rec = read_record(run)
    with _open(run, tmp_path, 0.3) as page:
        _body_drawn(page)
        assert _covered(page, "objects").mean() > 0.002  # food, rock, walls
        # each fish's intention at the frame shown, labelled over it
        labels = page.evaluate("window.zoetic.extras()")["labels"]
        period = np.searchsorted(rec.period_times, rec.times[0] + 0.3 + 1e-9, "right") - 1
        names = rec.labels["intention"]
        assert labels == [names[int(rec.scalars[a.name]["intention"][period])] for a in rec.animals]
        assert page.locator("#zoetic .label").first.is_visible()
        mind = _panel(page, "mind")
        fish = rec.animals[0].name
        assert mind["who"] == fish and mind["drives"] == ["hunger", "libido", "fear"]
        assert mind["periods"] == len(rec.period_times)
        codes = set(rec.scalars[fish]["intention"].astype(int).tolist())
        assert set(mind["intentions"]) == {names[c] for c in codes}


def test_a_pursuit_draws_the_animals_and_the_predators_gaze(tmp_path):
    run = _run(tmp_path, "chase", ["pursue", "--seconds", "0.4", "--no-video"])
    rec = read_record(run)
    assert rec.scalars["predator"]["eye_pos"].shape == (len(rec.period_times), 2, 3)
    with _open(run, tmp_path, 0.3) as page:
        _body_drawn(page)
        assert page.evaluate("window.zoetic.extras()")["gaze"]
        gaze = _covered(page, "gaze")
        assert gaze.mean() > 0.0005, f"the gaze rays cover {100 * gaze.mean():.3f}%"
        assert "eye_pos 1" not in str(page.evaluate("window.zoetic.plots()"))  # not plotted


@pytest.mark.slow
def test_a_stunt_draws_the_dolphin_ball_bar_and_splash(tmp_path):
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.behavior.training import rest_abstraction
    from zoetic.bodies import load_animal

    dolphin = load_animal("dolphin")
    rep = Repertoire(dolphin.name, tuple(dolphin.actuator_names))
    rep.add("do-nothing", rest_abstraction(dolphin), 1.0)
    rep.save(tmp_path / "memory")
    (tmp_path / "drop.toml").write_text(STUNT)
    args = ["dolphin", "--memory", str(tmp_path / "memory"), "--trick", str(tmp_path / "drop.toml")]
    run = _run(tmp_path, "stunt", ["stunt", *args, "--budget", "2", "--no-video"])
    rec = read_record(run)
    splash = rec.scalars["dolphin"]["splash"]
    assert splash.max() > 0 and len(splash) == len(rec.times)  # it fell in
    hit = float(rec.times[np.argmax(splash > 0)] - rec.times[0])
    with _open(run, tmp_path, hit + 0.08) as page:
        _body_drawn(page)
        assert _covered(page, "objects").mean() > 0.002  # the ball and the bar
        drops = page.evaluate("window.zoetic.extras()")["drops"]
        assert drops > 0
        # as many drops in the air as the spray model's ballistics give from the page's data
        sp = page.evaluate("JSON.parse(document.getElementById('zoetic-data').textContent).splash")
        dt = hit + 0.08 - np.array(sp["t0"])
        y = np.array(sp["p0"]).reshape(-1, 3)[:, 1] + np.array(sp["v0"]).reshape(-1, 3)[:, 1] * dt
        assert drops == np.sum((dt >= 0) & (y - 0.5 * sp["gravity"] * dt**2 >= sp["level"]))
        spray = _covered(page, "spray")
        assert spray.mean() > 0.0002, f"the spray covers {100 * spray.mean():.3f}%"
        page.evaluate("window.zoetic.setTime(0)")  # before it fell in: no drops
        assert page.evaluate("window.zoetic.extras()")["drops"] == 0


@pytest.mark.slow
def test_a_san_creature_draws_its_links_and_commands(tmp_path):
    args = ["walker", "--trials", "2", "--top", "1", "--seconds", "0.5", "--workers", "1"]
    run = _run(tmp_path, "san", ["san", "search", *args, "--no-video"])
    with _open(run, tmp_path, 0.2) as page:
        _body_drawn(page)
        _activations(page, len(read_record(run).creatures[0].actuators))
