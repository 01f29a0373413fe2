"""The web viewer: one offline HTML page, the local server, and a real (headless) Chromium."""

from __future__ import annotations

import base64
import contextlib
import dataclasses
import json
import re
import shutil
import threading
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from zoetic.cli import main
from zoetic.record import read_record
from zoetic.runs import simulate_run
from zoetic.viz.gltf import scene_glb, write_glb
from zoetic.viz.scene import load_scene
from zoetic.viz.viewer import viewer_data
from zoetic.web.page import page_html
from zoetic.web.server import make_server

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
# WebGL without a GPU: ANGLE on SwiftShader, Chromium's software rasteriser
WEBGL_FLAGS = [
    "--use-gl=angle",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--ignore-gpu-blocklist",
]


@contextlib.contextmanager
def viewer_page(html: Path):
    """Open a viewer page in headless Chromium (800 x 500) once it says it is ready; yield the
    page and the list its script errors are collected in (asserted empty at the start)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=WEBGL_FLAGS, headless=True)
        try:
            page = browser.new_page(viewport={"width": 800, "height": 500})
            errors: list[str] = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(html.as_uri())
            page.wait_for_function(
                "window.zoetic && (window.zoetic.ready || window.zoetic.error)", timeout=30_000
            )
            assert page.evaluate("window.zoetic.error") is None and not errors, errors
            yield page, errors
        finally:
            browser.close()


@pytest.fixture(scope="module")
def shark_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("shark")
    simulate_run("shark", "wave", 2.0, out)
    return out


def test_the_page_is_self_contained_and_carries_the_run(shark_run, tmp_path):
    html = tmp_path / "view.html"
    assert main(["view", str(shark_run), "--html", str(html), "--fps", "15"]) == 0
    text = html.read_text()
    assert not re.search(r"<(script|link|img)[^>]+(src|href)=", text)  # nothing fetched
    data = json.loads(re.search(r"id='zoetic-data'[^>]*>(.*?)</script>", text, re.S).group(1))
    scene = load_scene(shark_run, fps=15)
    assert base64.b64decode(data["glb"]) == scene_glb(scene)
    assert data["frames"] == 31 and data["duration"] == pytest.approx(2.0)
    acts = np.array(data["animals"][0]["activations"]).reshape(31, -1)
    np.testing.assert_allclose(acts, scene.animals[0].activations, atol=5e-4)
    # the time plots: the record's motion of the shark at every recorded instant
    rec = read_record(shark_run)
    plots = data["plots"]
    assert list(plots["animals"]) == ["shark"]
    assert list(plots["animals"]["shark"])[:2] == ["speed", "height"]  # water: no surface
    np.testing.assert_allclose(plots["times"], rec.period_times - rec.times[0], atol=1e-4)
    np.testing.assert_allclose(
        plots["animals"]["shark"]["roll"], rec.scalars["shark"]["roll"], atol=1e-4
    )
    assert plots["units"]["speed"] == "m/s" and plots["units"]["pitch"] == "deg"


def test_no_text_of_the_run_can_close_the_data_element(shark_run):
    title = "a </script><!-- <script> b"
    scene = dataclasses.replace(load_scene(shark_run, fps=5), title=title)
    text = page_html(viewer_data(scene))
    data = re.search(r"id='zoetic-data'[^>]*>(.*?)</script>", text, re.S).group(1)
    assert json.loads(data)["title"] == title
    assert "&lt;/script>" in text.split("</title>")[0]


def test_without_the_built_script_the_cli_says_how_to_build_it(
    shark_run, tmp_path, monkeypatch, capsys
):
    import zoetic.web.page as page

    monkeypatch.setattr(page, "_STATIC", tmp_path / "nowhere")
    assert main(["view", str(shark_run), "--html", str(tmp_path / "v.html")]) == 2
    assert "npm run build" in capsys.readouterr().err
    assert not (tmp_path / "v.html").exists()


def test_the_server_answers_the_page_and_nothing_else(shark_run):
    page = "<html>zoetic</html>"
    server = make_server(page, 0)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        url = f"http://127.0.0.1:{server.server_address[1]}/"
        with urllib.request.urlopen(url, timeout=5) as r:
            assert r.status == 200 and r.read().decode() == page
        with pytest.raises(urllib.error.HTTPError, match="404"):
            urllib.request.urlopen(url + "other", timeout=5)
    finally:
        server.shutdown()
        server.server_close()


def _canvas(page) -> np.ndarray:
    from io import BytesIO

    from PIL import Image

    png = page.locator("#zoetic > canvas").screenshot()
    return np.asarray(Image.open(BytesIO(png)).convert("RGB"), float)


def _check_plots(page, who: str, what: list[str], points: int) -> None:
    """The time plots show ``who``'s ``what`` with ``points`` samples each, drawn, and their
    cursor follows the time shown."""
    from io import BytesIO

    from PIL import Image

    info = page.evaluate("window.zoetic.plots()")
    assert info["who"] == who and [c["what"] for c in info["charts"]] == what, info
    assert all(c["points"] == points and c["max"] > c["min"] for c in info["charts"]), info
    chart = page.locator("#plots canvas").first
    shots = []
    for t in (0.05, 0.45):
        page.evaluate(f"window.zoetic.pause(); window.zoetic.setTime({t})")
        shots.append(np.asarray(Image.open(BytesIO(chart.screenshot())).convert("RGB"), float))
    assert shots[0].std() > 10, "the strip chart is blank"
    assert (np.abs(shots[1] - shots[0]).max(axis=2) > 40).mean() > 0.002, "the cursor stood"
    box, view = page.locator("#plots").bounding_box(), page.locator("#panel").bounding_box()
    assert box["x"] > view["x"] + view["width"] or box["y"] > view["y"] + view["height"]


def test_the_viewer_draws_and_scrubs_in_chromium(shark_run, tmp_path):

    assert Path(CHROMIUM).exists(), (
        f"{CHROMIUM} not found: the browser test needs Chromium "
        "(Debian: apt-get install -y chromium)"
    )
    html = tmp_path / "view.html"
    html.write_text(page_html(viewer_data(load_scene(shark_run, fps=30), read_record(shark_run))))
    glb = write_glb(load_scene(shark_run, fps=30), tmp_path / "s.glb")
    with viewer_page(html) as (page, errors):
        page.keyboard.press(" ")  # pause, then move the timeline as a user would
        assert page.inner_text("#play") == "play"
        assert page.evaluate("window.zoetic.displaySkins()") == 1  # the shark's skin, drawn here
        t0 = page.evaluate("window.zoetic.time()")
        page.keyboard.press("ArrowRight")  # one frame on
        assert page.evaluate("window.zoetic.time()") == pytest.approx(min(t0 + 1 / 30, 2))
        page.uncheck("#follow")  # a still camera: the shark swims across the picture
        page.eval_on_selector(
            "#timeline", "s => { s.value = 0; s.dispatchEvent(new Event('input')); }"
        )
        page.wait_for_timeout(100)
        start = _canvas(page)
        assert start.std() > 10, "the canvas is blank"
        page.screenshot(path=str(tmp_path / "viewer-start.png"))
        page.eval_on_selector(
            "#timeline", "s => { s.value = 1.5; s.dispatchEvent(new Event('input')); }"
        )
        page.wait_for_timeout(100)
        later = _canvas(page)
        page.screenshot(path=str(tmp_path / "viewer-1.5s.png"))
        assert "t = 1.50 s" in page.inner_text("#panel")
        changed = np.abs(later - start).max(axis=2) > 20
        print(f"{100 * changed.mean():.2f}% of the pixels changed")
        assert changed.mean() > 0.005, "moving the timeline did not change the picture"
        page.eval_on_selector(
            "#timeline", "s => { s.value = s.max; s.dispatchEvent(new Event('input')); }"
        )
        page.wait_for_timeout(100)
        end = _canvas(page)  # the last frame, not the first again (a looping clip wraps)
        assert (np.abs(end - start).max(axis=2) > 20).mean() > 0.005
        assert (np.abs(end - later).max(axis=2) > 20).mean() > 0.001
        _check_plots(page, "shark", ["speed", "height"], 201)
        # the exported .glb, read by three.js's own GLTFLoader
        b64 = base64.b64encode(glb.read_bytes()).decode()
        info = page.evaluate("b => window.zoetic.inspectGlb(b)", b64)
    from zoetic.viz.gltf import skin_joints

    animal = load_scene(shark_run).animals[0]
    joints = animal.positions.shape[1] + len(skin_joints(animal.skin)[2])  # nodes, fin tips
    assert info["skinned"] == 1 and info["meshes"] >= 2  # the shark and the sea floor
    assert info["animations"] == 1 and info["tracks"] == joints
    assert info["duration"] == pytest.approx(2.0, abs=1e-3)
    assert (tmp_path / "viewer-1.5s.png").stat().st_size > 1000


@pytest.mark.slow
def test_an_aquarium_plays_in_chromium_with_its_objects_and_events(tmp_path):
    """A tiny aquarium run, opened like any other: the page loads, draws the fishes, food,
    rock and walls, and lists the events up to the time shown."""

    from zoetic.record import Event, read_record, write_record

    run = tmp_path / "tank"
    assert (
        main(
            [
                "aquarium",
                "--fishes",
                "2",
                "--food",
                "2",
                "--obstacles",
                "1",
                "--seconds",
                "0.5",
                "--no-video",
                "--out",
                str(run),
            ]
        )
        == 0
    )
    rec = read_record(run)
    fish = rec.animals[0].name
    write_record(run, dataclasses.replace(rec, events=(Event(0.2, fish, "eat", "food 1"),)))
    html = tmp_path / "tank.html"
    assert main(["view", str(run), "--html", str(html), "--fps", "20"]) == 0
    scene = load_scene(run, fps=20)
    with viewer_page(html) as (page, errors):
        page.evaluate("window.zoetic.pause(); window.zoetic.setTime(0.1)")
        assert page.inner_text("#panel .events") == ""  # nothing has happened yet
        page.evaluate("window.zoetic.setTime(0.3)")
        assert page.inner_text("#panel .events") == f"0.2 s {fish} eat food 1"
        t = page.evaluate("window.zoetic.time()")  # 0.3 s: frame 6 at 20 fps
        states = page.inner_text("#panel .states").split("\n")
        assert states == [
            f"{a.name}: {scene.states[a.name]['intention'][6]}" for a in rec.animals
        ], (t, states)
        assert _canvas(page).std() > 10, "the canvas is blank"
        _check_plots(page, rec.animals[0].name, ["speed", "height"], len(rec.period_times))
        other = rec.animals[1].name
        page.select_option("#plot-who", other)  # another fish: its own charts
        assert page.evaluate("window.zoetic.plots()")["who"] == other
        page.screenshot(path=str(tmp_path / "tank.png"))
