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
