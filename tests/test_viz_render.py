"""The software renderer and the path plot: sizes, motion, the sea surface, files written."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.bodies import load_animal
from zoetic.errors import ZoeticError
from zoetic.physics import get_medium
from zoetic.viz.plots import plot_path
from zoetic.viz.render3d import Camera, render_frames, render_video, resample

SIZE = (160, 96)


def _track(body, shifts) -> np.ndarray:
    """Return (R, N, 3) positions: the rest pose moved by each (3,) shift."""
    rest = body.rest_pos - body.rest_pos.mean(axis=0)
    return rest[None] + np.asarray(shifts, float)[:, None, :]


def _frames(body, pos, medium, **kw) -> list[np.ndarray]:
    times = np.arange(len(pos) if isinstance(pos, np.ndarray) else len(pos[0])) * 0.1
    return list(render_frames(body, pos, times, get_medium(medium), size=SIZE, **kw))


def _mask(frame: np.ndarray, empty: np.ndarray) -> np.ndarray:
    """Return where a frame differs from the empty scene (the animal's pixels, not the clock)."""
    mask = np.abs(frame.astype(int) - empty.astype(int)).max(axis=2) > 12
    mask[:24] = False  # the time stamp differs from frame to frame
    return mask


@pytest.mark.parametrize("name", ["snake", "shark", "ray", "dolphin"])
def test_frames_have_the_requested_size_and_are_not_blank(name):
    body = load_animal(name)
    pos = _track(body, [[0, 0, 0], [0.1, 0, 0]]) + body.start_offset
    frames = _frames(body, pos, body.medium)
    assert len(frames) == 2
    for f in frames:
        assert f.shape == (SIZE[1], SIZE[0], 3) and f.dtype == np.uint8
        assert f.std() > 5 and len(np.unique(f.reshape(-1, 3), axis=0)) > 50


def test_animal_pixels_follow_the_animal_under_a_fixed_camera():
    body = load_animal("shark")
    cam = Camera(target=(0.0, 0.0, 0.0), azimuth=90.0, elevation=10.0, distance=3.0)
    pos = _track(body, [[-0.6, 0, 0], [0.6, 0, 0], [0.0, 0, 0]])
    pos[2] = np.nan  # a failed candidate draws nothing: the empty scene
    left, right, empty = _frames(body, pos, "water", camera=cam)
    xs = [np.nonzero(_mask(f, empty))[1] for f in (left, right)]
    assert min(map(len, xs)) > 50
    assert xs[1].mean() - xs[0].mean() > 20  # +x is to the right in a view from the right side


def test_several_animals_with_labels_and_buoys():
    body = load_animal("shark")
    pos = [_track(body, [[0, 0, 0.5 * k]] * 2) for k in range(3)]
    frames = _frames([body] * 3, pos, "water", labels=["a", "b", "c"], markers=[[1, 0, 0]])
    one = _frames(body, pos[0], "water")
    assert frames[0].shape == one[0].shape and not np.array_equal(frames[0], one[0])


def test_the_sea_surface_tints_what_lies_beneath():
    body = load_animal("dolphin")
    cam = Camera(target=(0.0, 0.0, 0.0), elevation=20.0, distance=3.0)
    pos = _track(body, [[0, 0.4, 0], [0, -0.4, 0], [0, 0, 0]])
    pos[2] = np.nan
    above, below, empty = _frames(body, pos, "sea", camera=cam, colors=["white"])
    col = [f[_mask(f, empty)].mean(axis=0) for f in (above, below)]
    assert col[0].sum() - col[1].sum() > 60  # darker under the water
    assert (col[1][2] - col[1][0]) - (col[0][2] - col[0][0]) > 20  # and bluer
    assert empty[: SIZE[1] // 10].mean() > empty[-SIZE[1] // 3 :].mean() + 30  # sky over sea


def test_render_video_writes_a_readable_mp4(tmp_path):
    import imageio.v2 as imageio

    body = load_animal("snake")
    times = np.linspace(0.0, 1.0, 6)
    pos = _track(body, np.outer(times, [0.3, 0, 0]))
    out = render_video(body, pos, times, "ground", tmp_path / "v.mp4", fps=12, size=SIZE)
    frames = imageio.mimread(out, memtest=False)
    assert len(frames) == 13 and frames[0].shape == (SIZE[1], SIZE[0], 3)


def test_resample_interpolates_linearly():
    times = np.array([0.0, 1.0])
    pos = np.zeros((2, 1, 3))
    pos[1] = 1.0
    t, (p,) = resample([pos], times, fps=4)
    assert np.allclose(t, [0, 0.25, 0.5, 0.75, 1.0])
    assert np.allclose(p[:, 0, 0], t)


def test_mismatched_positions_are_an_error():
    body = load_animal("shark")
    with pytest.raises(ZoeticError, match="positions"):
        next(render_frames(body, np.zeros((3, 5, 3)), np.arange(3.0), "water"))


def test_plot_path_writes_a_png(tmp_path):
    t = np.linspace(0, 4, 50)
    com = np.stack([t, 0 * t, np.sin(t)], axis=1)
    out = plot_path(com, tmp_path / "p" / "path.png", targets=[[1, 1]], starts=[0, 25], title="x")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 5000
    two = plot_path([com, com + 1], tmp_path / "two.png")
    assert two.exists() and not list(tmp_path.glob("*.tmp"))


def test_a_controller_plot_shows_a_few_periods_of_its_rhythm():
    from zoetic.viz.learning import shown_window

    t = np.linspace(0.0, 10.0, 400)
    u = (np.sin(2 * np.pi * 3.0 * t) > 0).astype(float)[:, None]
    assert 0.8 < shown_window(t, u) < 1.3  # three 3 Hz strokes, not thirty
    assert shown_window(t, np.full((400, 1), 0.5)) == 10.0  # no rhythm: all of it


def test_a_clip_that_ends_in_the_air_is_not_settled():
    from zoetic.viz.stunts import settled_after

    t = np.linspace(0.0, 2.0, 21)
    y = np.where((t > 0.5) & (t < 1.2), 1.0, -1.0)  # out of the water from 0.6 to 1.1 s
    pos = np.zeros((21, 3, 3))
    pos[..., 1] = y[:, None]
    assert settled_after(pos, t, 0.0) == pytest.approx(1.2)
    pos[-1, :, 1] = 0.5  # still in the air at the end
    assert settled_after(pos, t, 0.0) is None


def test_tags_of_animals_on_top_of_each_other_do_not_overlap():
    from PIL import Image, ImageDraw

    from zoetic.viz.paint import label_font, place_tags
    from zoetic.viz.render3d import look_at

    draw = ImageDraw.Draw(Image.new("RGB", (320, 180)))
    eye = np.array([0.0, 0.0, 5.0])
    view = (eye, look_at(eye, np.zeros(3)), 160.0, (320, 180))
    fish = [np.array([[0.0, 0.0, 0.0], [0.1 * k, 0.05, 0.0]]) for k in range(5)]  # a huddle
    clock = (0, 0, 120, 30)
    boxes = place_tags(
        draw,
        [(f"fish {k}", (255, 255, 255)) for k in range(5)],
        fish,
        view,
        label_font(12),
        [clock],
    )
    assert len(boxes) == 6  # every tag found room, beside the clock's box
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert not (a[0] < b[2] and a[2] > b[0] and a[1] < b[3] and a[3] > b[1])


def test_smooth_shading_normals_turn_gradually_across_a_closed_surface():
    """On a cube of 12 outward triangles, two faces across an edge meet at 90 deg; their
    shading normals (means of vertex normals) point outward and meet at less than that."""
    from zoetic.viz.render3d import smooth_normals

    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    n = np.cross(v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    centres = v[faces].mean(axis=1)
    inward = np.einsum("fk,fk->f", n, centres) < 0  # wind every face outward
    faces[inward], n[inward] = faces[inward][:, ::-1], -n[inward]
    s = smooth_normals(n, faces, np.ones(len(faces), bool), len(v))
    assert np.allclose(np.linalg.norm(s, axis=1), 1.0)
    assert np.all(np.einsum("fk,fk->f", s, centres) > 0)  # outward
    edge = [(i, j) for i in range(12) for j in range(i) if len(set(faces[i]) & set(faces[j])) == 2]
    across = [(i, j) for i, j in edge if abs(np.dot(n[i], n[j])) < 1e-9]
    assert across
    assert all(np.dot(s[i], s[j]) > 0.2 for i, j in across)  # was cos 90 deg = 0


def test_a_saved_figure_is_laid_out_tightly_once(tmp_path):
    """save_figure writes what tight_layout then savefig write, pixel for pixel, and leaves no
    layout engine behind (one that savefig would run, drawing the figure an extra time)."""
    import io

    from PIL import Image

    from zoetic.viz.plots import new_figure, save_figure

    def draw():
        fig = new_figure((4.0, 3.0), dpi=80)
        for k in range(2):
            ax = fig.add_subplot(2, 1, k + 1)
            ax.plot([0, 1, 2], [k, 2, 1], label=f"line {k}")
            ax.set_ylabel("a long label that needs room")
            ax.legend()
        return fig

    fig = draw()
    save_figure(fig, tmp_path / "a.png")
    assert fig.get_layout_engine() is None
    reference = draw()
    reference.tight_layout()
    buf = io.BytesIO()
    reference.savefig(buf, format="png")
    ours = np.asarray(Image.open(tmp_path / "a.png"))
    theirs = np.asarray(Image.open(buf))
    assert ours.shape == theirs.shape and np.array_equal(ours, theirs)
