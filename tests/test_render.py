"""The rasteriser: projection lands where the pinhole model says, nearer surfaces hide farther
ones, and an animal's colour shows in the picture."""

from __future__ import annotations

import numpy as np

from zoetic.bodies import load_animal
from zoetic.physics.objects import Box, Cylinder
from zoetic.physics.world import placed_pose
from zoetic.render import Cameras, look_rotation, project, render, world_mesh


def _cam(size=64, fov=np.pi / 2, eye=(0.0, 0.0, 0.0), forward=(1.0, 0.0, 0.0)):
    return Cameras(
        np.array([eye]), look_rotation(np.array([forward])), np.array([fov]), (size, size)
    )


def test_a_point_projects_to_the_expected_pixel_and_a_triangle_covers_it():
    cam = _cam()
    # fov 90 deg, 64 px: focal 32 px; a point 1 m ahead, 0.5 m to the left (+z), 0.25 m up
    uv, z = project([[1.0, 0.25, 0.5]], cam)
    assert np.allclose(uv[0, 0], [32 - 16, 32 - 8]) and np.isclose(z[0, 0], 1.0)
    c = np.array([1.0, 0.25, 0.5])
    tri = np.array([c + [0, -0.05, 0.05], c + [0, -0.05, -0.05], c + [0, 0.06, 0.0]])
    img = render(tri, [[0, 1, 2]], [[1.0, 0.0, 0.0]], cam)[0]
    red = (img[..., 0] > 200) & (img[..., 1] < 50)
    rows, cols = np.nonzero(red)
    assert red[24, 16] and abs(cols.mean() - 16) < 1.0 and abs(rows.mean() - 24) < 2.0
    assert red.sum() < 20  # and nothing else


def test_nearer_surfaces_hide_farther_ones_whatever_the_drawing_order():
    cam = _cam()

    def quad(x):
        return np.array([[x, -1, -1], [x, -1, 1], [x, 1, 1], [x, 1, -1.0]])

    v = np.concatenate([quad(3.0), quad(2.0)])
    t = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    near_green = np.array([[1, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0.0]])
    for order in (np.arange(4), np.arange(4)[::-1]):
        img, depth = render(v, t[order], near_green[order], cam, with_depth=True)
        assert img[0, 32, 32, 1] == 255 and img[0, 32, 32, 0] == 0
        assert np.isclose(depth[0, 32, 32], 2.0)


def test_an_animal_shows_in_its_colour_among_rocks_and_seaweed_with_fog():
    shark = load_animal("shark")
    pos = placed_pose(shark, (0.0, 0.0, 0.0))
    com = pos.mean(0)
    mesh = world_mesh(
        [shark],
        [pos],
        [(0.9, 0.15, 0.1)],
        [
            Box((com[0], -1.5, com[2] + 3), (0.5, 0.5, 0.5)),
            Cylinder((com[0] + 1, -1.0, com[2] - 3), 0.05, 2.0),
        ],
        floor=(0.0, 0.0, -2.0, 20.0),
    )
    eye = com + np.array([0.0, 0.5, 2.5])
    cam = _cam(96, np.radians(60), eye, com - eye)
    clear = render(mesh.vertices, mesh.triangles, mesh.colors, cam)[0].astype(int)
    foggy = render(mesh.vertices, mesh.triangles, mesh.colors, cam, visibility=1.0)[0].astype(int)
    reddish = (clear[..., 0] > 2 * clear[..., 1]) & (clear[..., 0] > 90)
    assert reddish[40:56, 30:66].mean() > 0.3  # the fish in the middle of the picture
    assert reddish.sum() > 50 and (foggy[..., 0] > 2 * foggy[..., 1]).sum() < reddish.sum()
    assert (mesh.owner == 0).sum() == len(shark.faces)


# ---------------------------------------------------------------- display skins


def test_a_skin_moves_rigidly_with_its_lattice_and_covers_it_smoothly():
    from zoetic.render.skin import body_skin, skin_vertices

    shark = load_animal("shark")
    skin = body_skin(shark)
    np.testing.assert_allclose(skin.weight.sum(axis=1), 1.0, atol=1e-6)
    assert len(skin.triangles) > 10 * len(shark.faces)  # subdivided, plus fins
    a = 0.7
    rot = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1.0]])
    moved = shark.rest_pos @ rot.T + [1.0, -2.0, 0.5]
    both = skin_vertices(skin, np.stack([shark.rest_pos, moved]))  # batched over frames
    np.testing.assert_allclose(both[1], both[0] @ rot.T + [1.0, -2.0, 0.5], atol=1e-5)
    # the dorsal fin stands above the lattice's back (an affine extension of the nodes)
    assert both[0][:, 1].max() > shark.rest_pos[:, 1].max() + 0.05


def test_species_on_one_lattice_look_different():
    from zoetic.render.skin import body_skin

    shark = load_animal("shark")
    pred, prey = body_skin(shark, "shark"), body_skin(shark, "minnow")
    # the minnow is golden, the shark grey: their mean colours differ clearly
    assert np.linalg.norm(pred.colors.mean(0) - prey.colors.mean(0)) > 0.15
    assert prey.colors[:, 0].mean() > prey.colors[:, 2].mean() + 0.2  # warm
    for name in ("dolphin", "ray", "snake"):
        skin = body_skin(load_animal(name))
        assert np.ptp(skin.colors, axis=0).max() > 0.3  # a belly and markings, not one colour


def test_a_bad_look_file_names_the_file_and_the_fin(tmp_path):
    import pytest

    from zoetic.render.skin import LookError, read_look

    bad = tmp_path / "bad.toml"
    bad.write_text(
        'name = "bad"\ncolor = [1, 2, 3]\nbelly = [4, 5, 6]\n'
        '[[fin]]\nname = "dorsal"\npoints = [{a = 1.0}, {b = 0.5}, {c = 1.0}]\n'
    )
    with pytest.raises(LookError, match=r"bad\.toml: fin 1.*corner 2.*sum to 0\.5"):
        read_look(bad)
