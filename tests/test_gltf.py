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
from zoetic.control import save_controller, wave_controller
from zoetic.io import write_json, write_toml
from zoetic.runs import simulate_run
from zoetic.viz.gltf import MIRROR, scene_glb, write_glb
from zoetic.viz.scene import load_scene

WEB = Path(__file__).resolve().parents[1] / "web"
DTYPES = {5126: np.float32, 5125: np.uint32, 5123: np.uint16, 5121: np.uint8}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


@pytest.fixture(scope="module")
def shark_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("shark")
    simulate_run("shark", "wave", 1.0, out, video=False)
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
    scene = load_scene(shark_run, fps=20)
    path = write_glb(scene, tmp_path / "s.glb")
    g, blob = _load(path)
    assert g.asset.version == "2.0" and len(g.buffers) == 1 and g.buffers[0].byteLength == len(blob)
    animal = scene.animals[0]
    n, frames = animal.positions.shape[1], len(scene.times)
    assert frames == 21
    (skin,) = g.skins
    assert len(skin.joints) == n
    (anim,) = g.animations
    assert len(anim.channels) == n and {c.target.path for c in anim.channels} == {"translation"}
    times = _read(g, blob, anim.samplers[0].input)[:, 0]
    np.testing.assert_allclose(times, np.arange(frames) / 20, atol=1e-6)
    assert g.accessors[anim.samplers[0].input].max == [pytest.approx(1.0)]
    for ch in anim.channels:  # every node's track is its node's positions, z mirrored
        i = skin.joints.index(ch.target.node)
        track = _read(g, blob, anim.samplers[ch.sampler].output)
        np.testing.assert_allclose(track, animal.positions[:, i] * MIRROR, atol=1e-6)
    # the mesh: rest vertices at frame 0 with exact bounds, faces reversed, one joint per vertex
    (mesh_node,) = [nd for nd in g.nodes if nd.skin is not None]
    prim = g.meshes[mesh_node.mesh].primitives[0]
    rest = _read(g, blob, prim.attributes.POSITION)
    np.testing.assert_allclose(rest, animal.positions[0] * MIRROR, atol=1e-6)
    acc = g.accessors[prim.attributes.POSITION]
    assert acc.min == pytest.approx(rest.min(0).tolist()) and acc.max == pytest.approx(
        rest.max(0).tolist()
    )
    faces = _read(g, blob, prim.indices).reshape(-1, 3)
    np.testing.assert_array_equal(faces, animal.faces[:, ::-1])
    np.testing.assert_array_equal(_read(g, blob, prim.attributes.JOINTS_0)[:, 0], np.arange(n))
    ibm = _read(g, blob, skin.inverseBindMatrices).reshape(n, 4, 4)  # column-major
    np.testing.assert_allclose(ibm[:, 3, :3], -rest, atol=1e-6)
    colour = g.materials[prim.material].pbrMetallicRoughness.baseColorFactor
    np.testing.assert_allclose(colour[:3], (np.array(animal.color) / 255) ** 2.2, atol=1e-4)
    assert g.scenes[0].extras["fps"] == 20
    names = {nd.name for nd in g.nodes}
    assert "sea floor" in names and "ground" not in names  # the shark swims in open water


def test_ground_targets_and_a_learning_run(tmp_path):
    """A run known by its controller (config.toml) is simulated again; a track run has targets."""
    body = load_animal("snake")
    save_controller(wave_controller(body), tmp_path / "controller.json")
    write_toml(
        tmp_path / "config.toml",
        {"run": {"animal": "snake"}, "task": {"name": "crawl", "horizon": 0.5}},
    )
    scene = load_scene(tmp_path, fps=10)
    assert scene.kind == "learn" and len(scene.times) == 6
    g, _ = _load(write_glb(scene, tmp_path / "snake.glb"))
    assert "ground" in {nd.name for nd in g.nodes}
    (tmp_path / "config.toml").unlink()
    write_json(tmp_path / "summary.json", {"animal": "snake", "simulated_s": 0.5,
                                           "targets_xz": [[1, 2], [3, -1]], "reached": 1,
                                           "targets": 2})  # fmt: skip
    scene = load_scene(tmp_path, fps=10)
    assert scene.kind == "track" and scene.numbers["targets_reached"] == "1/2"
    g, blob = _load(write_glb(scene, tmp_path / "track.glb"))
    marks = [nd for nd in g.nodes if nd.name.startswith("target-")]
    assert [m.translation[0] for m in marks] == [1, 3]
    assert [m.translation[2] for m in marks] == [-2, 1]  # z mirrored


def test_the_khronos_validator_finds_no_issue(shark_run, tmp_path):
    node = shutil.which("node")
    validator = WEB / "node_modules" / "gltf-validator"
    assert node and validator.exists(), (
        "the Khronos glTF validator is installed by ./run.sh (npm ci in web/; needs Node.js)"
    )
    path = write_glb(load_scene(shark_run), tmp_path / "s.glb")
    script = (
        "const v = require(process.argv[1]); const fs = require('fs');"
        "v.validateBytes(new Uint8Array(fs.readFileSync(process.argv[2])))"
        ".then(r => console.log(JSON.stringify(r.issues)));"
    )
    out = subprocess.run([node, "-e", script, str(validator), str(path)], capture_output=True,
                         text=True, timeout=60, check=True)  # fmt: skip
    issues = json.loads(out.stdout)
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]


def test_export_cli(shark_run, tmp_path, capsys):
    out = tmp_path / "s.glb"
    assert main(["export", str(shark_run), "--gltf", str(out), "--fps", "10"]) == 0
    assert out.read_bytes() == scene_glb(load_scene(shark_run, fps=10))
    assert main(["export", str(tmp_path), "--gltf", str(tmp_path / "x.glb")]) == 2
    assert "no trajectory.npz" in capsys.readouterr().err


def test_a_san_creature_is_rigid_links_posed_frame_by_frame(tmp_path):
    from zoetic.san import load_creature
    from zoetic.san.network import random_network, save_network

    creature = load_creature("walker")
    net = random_network(creature, np.random.default_rng(1))
    save_network(net.with_params(info={"seconds": 0.5, "seed": 0}), tmp_path / "san.json")
    scene = load_scene(tmp_path, fps=20)
    (c,) = scene.creatures
    assert scene.kind == "san" and len(scene.times) == 11 and len(c.links) == 6
    g, blob = _load(write_glb(scene, tmp_path / "san.glb"))
    (anim,) = g.animations
    link = c.links[2]
    node = next(i for i, nd in enumerate(g.nodes) if nd.name.endswith(f"-{link.name}"))
    paths = {ch.target.path: anim.samplers[ch.sampler].output for ch in anim.channels
             if ch.target.node == node}  # fmt: skip
    np.testing.assert_allclose(_read(g, blob, paths["translation"]),
                               link.translations * MIRROR, atol=1e-6)  # fmt: skip
    q = _read(g, blob, paths["rotation"])  # about z for a walker in the vertical plane
    np.testing.assert_allclose(2 * np.arctan2(q[:, 2], q[:, 3]), link.angles, atol=1e-5)
    assert np.ptp(link.angles) > 0  # the links move
    assert "ground" in {nd.name for nd in g.nodes}
