"""glTF export: a strict reader (pygltflib), the Khronos validator, the data round trip, the CLI."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pygltflib
import pytest

from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.control import wave_controller
from zoetic.runs import simulate_run
from zoetic.viz.gltf import MIRROR, scene_glb, write_glb
from zoetic.viz.scene import load_scene

WEB = Path(__file__).resolve().parents[1] / "web"
DTYPES = {5126: np.float32, 5125: np.uint32, 5123: np.uint16, 5121: np.uint8}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


@pytest.fixture(scope="module")
def shark_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("shark")
    simulate_run("shark", "wave", 1.0, out)
    return out


def _read(g: pygltflib.GLTF2, blob: bytes, k: int) -> np.ndarray:
    """Return accessor ``k`` as an array (count, width), read from the binary chunk."""
    acc = g.accessors[k]
    view = g.bufferViews[acc.bufferView]
    dt, width = DTYPES[acc.componentType], WIDTH[acc.type]
    start = view.byteOffset + acc.byteOffset
    n = acc.count * width
    assert start + n * np.dtype(dt).itemsize <= view.byteOffset + view.byteLength
    return np.frombuffer(blob, dt, n, start).reshape(acc.count, width)


def _load(path: Path) -> tuple[pygltflib.GLTF2, bytes]:
    g = pygltflib.GLTF2().load(str(path))
    return g, g.binary_blob()


def test_the_glb_holds_the_run_frame_by_frame(shark_run, tmp_path):
    from zoetic.render.skin import skin_vertices
    from zoetic.viz.gltf import skin_joints

    scene = load_scene(shark_run, fps=20)
    path = write_glb(scene, tmp_path / "s.glb")
    g, blob = _load(path)
    assert g.asset.version == "2.0" and len(g.buffers) == 1 and g.buffers[0].byteLength == len(blob)
    animal = scene.animals[0]
    n, frames = animal.positions.shape[1], len(scene.times)
    assert frames == 21
    skin = animal.skin
    _, _, extra = skin_joints(skin)
    assert len(extra) > 0  # the fins' tips stand out of the lattice: joints of their own
    (gskin,) = g.skins
    assert len(gskin.joints) == n + len(extra)
    (anim,) = g.animations
    assert len(anim.channels) == len(gskin.joints)
    assert {c.target.path for c in anim.channels} == {"translation"}
    times = _read(g, blob, anim.samplers[0].input)[:, 0]
    np.testing.assert_allclose(times, np.arange(frames) / 20, atol=1e-6)
    assert g.accessors[anim.samplers[0].input].max == [pytest.approx(1.0)]
    tracks = np.zeros((len(gskin.joints), frames, 3))
    for ch in anim.channels:
        tracks[gskin.joints.index(ch.target.node)] = _read(
            g, blob, anim.samplers[ch.sampler].output
        )
    # the first n joints are the nodes, z mirrored
    np.testing.assert_allclose(tracks[:n].transpose(1, 0, 2), animal.positions * MIRROR, atol=1e-6)
    # the mesh: the skin at frame 0, exact bounds, triangles reversed, coloured per vertex
    (mesh_node,) = [nd for nd in g.nodes if nd.skin is not None]
    prim = g.meshes[mesh_node.mesh].primitives[0]
    rest = _read(g, blob, prim.attributes.POSITION)
    want = skin_vertices(skin, animal.positions.astype(float)) * MIRROR  # (R, V, 3)
    np.testing.assert_allclose(rest, want[0], atol=1e-5)
    acc = g.accessors[prim.attributes.POSITION]
    assert acc.min == pytest.approx(rest.min(0).tolist()) and acc.max == pytest.approx(
        rest.max(0).tolist()
    )
    faces = _read(g, blob, prim.indices).reshape(-1, 3)
    np.testing.assert_array_equal(faces, skin.triangles[:, ::-1])
    colours = _read(g, blob, prim.attributes.COLOR_0)
    np.testing.assert_allclose(colours, skin.colors**2.2, atol=1e-5)
    # skinning as a glTF viewer does it (translation-only joints) gives the skin at every frame
    ids = np.concatenate(
        [_read(g, blob, prim.attributes.JOINTS_0), _sets(g, blob, prim, "JOINTS")], 1
    )
    w = np.concatenate(
        [_read(g, blob, prim.attributes.WEIGHTS_0), _sets(g, blob, prim, "WEIGHTS")], 1
    )
    assert (w >= 0).all()
    np.testing.assert_allclose(w.sum(axis=1), 1.0, atol=1e-6)
    ibm = _read(g, blob, gskin.inverseBindMatrices).reshape(-1, 4, 4)  # column-major
    bind = -ibm[:, 3, :3]
    for r in (0, frames // 2, frames - 1):
        moved = rest + np.einsum(
            "vk,vkc->vc", w, tracks[ids.astype(int), r] - bind[ids.astype(int)]
        )
        np.testing.assert_allclose(moved, want[r], atol=1e-4)
    assert g.scenes[0].extras["fps"] == 20
    names = {nd.name for nd in g.nodes}
    assert "sea floor" in names and "ground" not in names  # the shark swims in open water


def _sets(g, blob, prim, what: str) -> np.ndarray:
    """Return the JOINTS_n or WEIGHTS_n sets after the first, side by side (V, 4 (s - 1))."""
    attrs = prim.attributes.__dict__ | getattr(prim.attributes, "_extra", {})
    more = []
    k = 1
    while attrs.get(f"{what}_{k}") is not None:
        more.append(_read(g, blob, attrs[f"{what}_{k}"]))
        k += 1
    return np.concatenate(more, 1) if more else np.zeros((len(_read(g, blob, prim.indices)), 0))


def test_ground_and_targets_of_a_tracking_record(tmp_path):
    """A snake on the ground with two targets: a checkered ground, and the targets where the
    record puts them (z mirrored)."""
    from zoetic.cli.records import targets, write_sequence_record
    from zoetic.physics import get_medium
    from zoetic.runs import run_controller

    body = load_animal("snake")
    ctrl = wave_controller(body)
    traj = run_controller(body, ctrl, 0.5, get_medium("ground"), body.dt)
    write_sequence_record(
        tmp_path,
        "track",
        body,
        traj.times,
        traj.positions[0],
        ctrl,
        targets([[1, 2], [3, -1]], 0.0),
        {"targets_reached": "1/2"},
    )
    scene = load_scene(tmp_path, fps=10)
    assert scene.kind == "track" and len(scene.times) == 6
    assert scene.numbers["targets_reached"] == "1/2"
    g, _ = _load(write_glb(scene, tmp_path / "track.glb"))
    assert "ground" in {nd.name for nd in g.nodes}
    marks = [nd for nd in g.nodes if nd.name.startswith("target-")]
    assert [m.translation[0] for m in marks] == [1, 3]
    assert [m.translation[2] for m in marks] == [-2, 1]  # z mirrored


def _validate(path: Path) -> dict:
    """Return the Khronos glTF validator's issues with a .glb."""
    node = shutil.which("node")
    validator = WEB / "node_modules" / "gltf-validator"
    assert node and validator.exists(), (
        "the Khronos glTF validator is installed by ./run.sh (npm ci in web/; needs Node.js)"
    )
    script = (
        "const v = require(process.argv[1]); const fs = require('fs');"
        "v.validateBytes(new Uint8Array(fs.readFileSync(process.argv[2])))"
        ".then(r => console.log(JSON.stringify(r.issues)));"
    )
    out = subprocess.run(
        [node, "-e", script, str(validator), str(path)],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    return json.loads(out.stdout)


def test_the_khronos_validator_finds_no_issue(shark_run, tmp_path):
    issues = _validate(write_glb(load_scene(shark_run), tmp_path / "s.glb"))
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]


def test_export_cli(shark_run, tmp_path, capsys):
    out = tmp_path / "s.glb"
    assert main(["export", str(shark_run), "--gltf", str(out), "--fps", "10"]) == 0
    assert out.read_bytes() == scene_glb(load_scene(shark_run, fps=10))
    assert main(["export", str(tmp_path), "--gltf", str(tmp_path / "x.glb")]) == 2
    assert "no run record" in capsys.readouterr().err


def test_a_san_creature_is_rigid_links_posed_frame_by_frame(tmp_path):
    from zoetic.cli.records import write_san_record
    from zoetic.san import load_creature
    from zoetic.san.network import random_network, save_network

    creature = load_creature("walker")
    net = random_network(creature, np.random.default_rng(1))
    save_network(net.with_params(info={"seconds": 0.5, "seed": 0}), tmp_path / "san.json")
    write_san_record(tmp_path, tmp_path / "san.json", fps=20)
    scene = load_scene(tmp_path, fps=20)
    (c,) = scene.creatures
    assert scene.kind == "san" and len(scene.times) == 11 and len(c.links) == 6
    g, blob = _load(write_glb(scene, tmp_path / "san.glb"))
    (anim,) = g.animations
    link = c.links[2]
    node = next(i for i, nd in enumerate(g.nodes) if nd.name.endswith(f"-{link.name}"))
    paths = {
        ch.target.path: anim.samplers[ch.sampler].output
        for ch in anim.channels
        if ch.target.node == node
    }
    np.testing.assert_allclose(
        _read(g, blob, paths["translation"]), link.translations * MIRROR, atol=1e-6
    )
    q = _read(g, blob, paths["rotation"])  # about z for a walker in the vertical plane
    np.testing.assert_allclose(2 * np.arctan2(q[:, 2], q[:, 3]), link.angles, atol=1e-5)
    assert np.ptp(link.angles) > 0  # the links move
    assert "ground" in {nd.name for nd in g.nodes}


# ---------------------------------------------- every kind of run, through the one record

STUNT = """name = "ball-lob"
requires = ["surface"]
horizon = 0.5
record_hz = 20.0
[start]
depth = 0.6
speed = 1.0
[trick]
segments = 2
durations = [0.1, 0.4]
[[objects]]
kind = "ball"
name = "beach-ball"
radius = 0.25
mass = 0.3
position = [0.6, 0.5, 0.0]
[[terms]]
kind = "apex_above_surface"
weight = -1.0
"""


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Path]:
    """One tiny run of each kind the record made viewable: aquarium, pursuit, stunt, SAN."""
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.behavior.training import rest_abstraction

    tmp = tmp_path_factory.mktemp("runs")
    out = {k: tmp / k for k in ("aquarium", "pursuit", "stunt", "san")}
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
                "0.3",
                "--no-video",
                "--out",
                str(out["aquarium"]),
            ]
        )
        == 0
    )
    assert main(["pursue", "--seconds", "0.3", "--no-video", "--out", str(out["pursuit"])]) == 0
    dolphin = load_animal("dolphin")
    rep = Repertoire(dolphin.name, tuple(dolphin.actuator_names))
    rep.add("do-nothing", rest_abstraction(dolphin), 1.0)
    rep.save(tmp / "memory")
    (tmp / "lob.toml").write_text(STUNT)
    assert (
        main(
            [
                "stunt",
                "dolphin",
                "--memory",
                str(tmp / "memory"),
                "--trick",
                str(tmp / "lob.toml"),
                "--budget",
                "2",
                "--no-video",
                "--out",
                str(out["stunt"]),
            ]
        )
        == 0
    )
    assert (
        main(
            [
                "san",
                "search",
                "walker",
                "--trials",
                "2",
                "--top",
                "1",
                "--seconds",
                "0.5",
                "--workers",
                "1",
                "--no-video",
                "--out",
                str(out["san"]),
            ]
        )
        == 0
    )
    return out


def _exported(run: Path, tmp_path: Path, fps: int = 10):
    """Export a run with the CLI; return the parsed glTF, its binary chunk and the Scene."""
    path = tmp_path / f"{run.name}.glb"
    assert main(["export", str(run), "--gltf", str(path), "--fps", str(fps)]) == 0
    scene = load_scene(run, fps=fps)
    assert path.read_bytes() == scene_glb(scene)
    g, blob = _load(path)
    return g, blob, scene


def _tracks(g, node: int) -> dict[str, int]:
    (anim,) = g.animations
    return {
        ch.target.path: anim.samplers[ch.sampler].output
        for ch in anim.channels
        if ch.target.node == node
    }


def test_an_aquarium_exports_its_fishes_food_rocks_and_events(runs, tmp_path):
    from zoetic.record import read_record
    from zoetic.viz.viewer import viewer_data

    rec = read_record(runs["aquarium"])
    g, blob, scene = _exported(runs["aquarium"], tmp_path)
    assert scene.kind == "aquarium" and len(g.skins) == 2 == len(rec.animals)
    assert {a.name for a in rec.animals} == set(rec.scalars)  # per-period scalars per fish
    fish = rec.animals[0].name
    assert set(rec.scalars[fish]) >= {"hunger", "fear", "intention", "alive"}
    assert len(rec.scalars[fish]["hunger"]) == len(rec.period_times) > 0
    kinds = [o.kind for o in rec.objects]
    assert kinds.count("food") == 2 and kinds.count("wall") == 4 and len(kinds) == 7
    food = next(i for i, nd in enumerate(g.nodes) if nd.name.startswith("food-"))
    k = [o.kind for o in scene.objects].index("food")
    tracks = _tracks(g, food)
    np.testing.assert_allclose(
        _read(g, blob, tracks["translation"]), scene.objects[k].positions * MIRROR, atol=1e-6
    )
    assert set(_read(g, blob, tracks["scale"]).ravel()) <= {0.0, 1.0}  # eaten: hidden
    data = viewer_data(scene)
    assert [a["name"] for a in data["animals"]] == [a.name for a in rec.animals]
    assert data["events"] == [[round(e.t, 3), e.who, e.what, e.detail] for e in rec.events]
    # each fish's intention at every frame, as held since its brain period began
    period = np.searchsorted(rec.period_times, scene.times + rec.times[0] + 1e-9, "right") - 1
    codes = rec.scalars[fish]["intention"][period].astype(int)
    names = rec.labels["intention"]
    assert data["states"][fish]["intention"] == [names[c] for c in codes]


def test_a_pursuit_exports_its_three_fishes_and_the_scenery(runs, tmp_path):
    from zoetic.record import read_record

    rec = read_record(runs["pursuit"])
    g, blob, scene = _exported(runs["pursuit"], tmp_path)
    assert [a.name for a in rec.animals] == ["predator", "prey", "distractor 1"]
    assert len(g.skins) == 3 and scene.kind == "pursuit"
    assert {"rock", "seaweed"} <= {o.kind for o in rec.objects}
    gaze = rec.scalars["predator"]["gaze"]
    assert gaze.shape == (len(rec.period_times), 4) and np.isfinite(gaze).all()
    (prey_skin,) = [s for s in g.skins if s.name == "prey"]
    (anim,) = g.animations
    ch = next(c for c in anim.channels if c.target.node == prey_skin.joints[0])
    np.testing.assert_allclose(
        _read(g, blob, anim.samplers[ch.sampler].output),
        scene.animals[1].positions[:, 0] * MIRROR,
        atol=1e-6,
    )


def test_a_stunt_exports_the_dolphin_and_its_moving_ball(runs, tmp_path):
    g, blob, scene = _exported(runs["stunt"], tmp_path)
    assert scene.kind == "stunt" and len(g.skins) == 1
    (ball,) = [o for o in scene.objects if o.kind == "ball"]
    assert ball.shape == "sphere" and ball.size == (0.25,) and len(ball.positions) > 1
    node = next(i for i, nd in enumerate(g.nodes) if nd.name.startswith("ball-"))
    np.testing.assert_allclose(
        _read(g, blob, _tracks(g, node)["translation"]), ball.positions * MIRROR, atol=1e-6
    )
    assert scene.animals[0].activations is not None


def test_a_san_search_run_exports_its_best_creature(runs, tmp_path):
    g, blob, scene = _exported(runs["san"], tmp_path)
    (c,) = scene.creatures
    assert scene.kind == "san" and not scene.animals and len(c.links) == 6
    assert {"metric", "speed_cm_s", "fell"} <= set(scene.numbers)
    assert len(g.animations[0].channels) == 2 * len(c.links)


def test_the_khronos_validator_finds_no_issue_in_any_kind_of_run(runs, tmp_path):
    for kind, run in runs.items():
        issues = _validate(write_glb(load_scene(run, fps=10), tmp_path / f"{kind}.glb"))
        assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, (kind, issues["messages"])


def test_every_kind_of_run_gives_the_viewer_its_page_data(runs):
    import base64

    from zoetic.viz.viewer import viewer_data

    for kind, run in runs.items():
        scene = load_scene(run, fps=10)
        data = viewer_data(scene)
        assert data["kind"] == scene.kind and data["frames"] == len(scene.times), kind
        assert base64.b64decode(data["glb"]) == scene_glb(scene), kind
        assert len(data["animals"]) == len(scene.movers) > 0, kind
        for a in data["animals"]:
            assert len(a["com"]) == 3 * len(scene.times), kind
