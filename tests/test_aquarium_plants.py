"""The tank's dynamic plants: seaweed strands stepped with the world, kept in the record, the
glTF export and the video (behavior.aquarium.plants)."""

from __future__ import annotations

import numpy as np
import pygltflib
import pytest

from zoetic.behavior.aquarium.plants import BLADES, FRINGE, is_weed
from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live
from zoetic.cli import main
from zoetic.errors import SimulationError
from zoetic.physics.objects import pack_statics


def _tank(plants: str = "dynamic", seed: int = 0):
    """Two fishes, a rock and a seaweed clump."""
    return build_tank(TankConfig(fishes=2, food=1, obstacles=2, seconds=0.5, seed=seed,
                                 plants=plants))  # fmt: skip


def test_dynamic_seaweed_is_no_solid_for_the_bodies_but_an_obstacle_for_the_minds():
    tank = _tank()
    assert "seaweed" in tank.static_names  # the minds avoid the clump (kind, center, size)
    assert not any(is_weed(s) for s in tank.world.statics)  # the bodies part its strands
    assert tank.plants is not None and tank.plants.pos.shape[0] == BLADES
    clump = tank.center[tank.static_names.index("seaweed")]
    size = tank.size[tank.static_names.index("seaweed")]
    anchors = tank.plants.anchors
    assert np.allclose(anchors[:, 1], clump[1] - size[1])  # on the seabed under the clump
    assert (np.hypot(*(anchors - clump)[:, [0, 2]].T) <= size[0] + FRINGE).all()


def test_static_plants_keep_the_fixed_cylinders():
    tank = _tank("static")
    assert tank.plants is None
    assert sum(is_weed(s) for s in tank.world.statics) == 1
    np.testing.assert_array_equal(pack_statics(tank.world.statics)[1], tank.center)


def test_an_unknown_plants_option_is_refused(tmp_path, capsys):
    with pytest.raises(SimulationError, match="plants must be one of dynamic, static"):
        _tank("swaying")
    code = main(["aquarium", "--plants", "swaying", "--out", str(tmp_path / "t"), "--no-video"])
    assert code == 2
    assert "plants must be one of" in capsys.readouterr().err


def test_the_strands_live_with_the_tank_and_are_the_same_for_a_seed():
    runs = [live(_tank()).plants for _ in range(2)]
    assert runs[0].shape == (11, BLADES, 11, 3)  # records every 0.05 s over 0.5 s
    np.testing.assert_array_equal(runs[0], runs[1])
    moved = np.abs(runs[0][-1] - runs[0][0]).max()
    assert 0.0 < moved < 0.5  # they stretch and start to sway, no more
    other = _tank(seed=1).plants
    assert not np.array_equal(other.anchors, _tank().plants.anchors)


def test_the_record_and_the_gltf_export_carry_the_strands(tmp_path):
    from zoetic.record import read_record
    from zoetic.viz.scene import load_scene

    out = tmp_path / "tank"
    args = ["aquarium", "--fishes", "2", "--food", "1", "--obstacles", "2", "--seconds", "0.3"]
    assert main([*args, "--plants", "dynamic", "--no-video", "--out", str(out)]) == 0
    rec = read_record(out)
    strands = [o for o in rec.objects if o.shape == "strand"]
    assert len(strands) == BLADES and all(o.kind == "seaweed" for o in strands)
    assert strands[0].positions.shape == (len(rec.times), 11, 3)
    assert not any(o.shape == "cylinder" for o in rec.objects)  # no fixed seaweed beside them
    path = tmp_path / "tank.glb"
    assert main(["export", str(out), "--gltf", str(path), "--fps", "10"]) == 0
    g = pygltflib.GLTF2().load_binary(str(path))
    blob = g.binary_blob()
    assert len(g.skins) == 2 + BLADES  # the two fishes and one skinned tube a strand
    name = "seaweed-"
    tube = next(n for n in g.nodes if n.name.startswith(name) and n.skin is not None)
    joints = g.skins[tube.skin].joints
    assert len(joints) == 11
    (anim,) = g.animations
    ch = next(c for c in anim.channels if c.target.node == joints[-1])
    acc = g.accessors[anim.samplers[ch.sampler].output]
    view = g.bufferViews[acc.bufferView]
    start = (view.byteOffset or 0) + (acc.byteOffset or 0)
    tip = np.frombuffer(blob[start : start + 12 * acc.count], np.float32).reshape(-1, 3)
    scene = load_scene(out, fps=10)
    k = next(i for i, o in enumerate(scene.objects) if o.name == tube.name.split("-", 2)[2])
    np.testing.assert_allclose(tip, scene.objects[k].positions[:, -1] * [1, 1, -1], atol=1e-6)
