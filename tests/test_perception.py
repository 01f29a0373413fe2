"""Animat vision: foveated eyes, colour recognition, saccades, vergence and stabilisation."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.bodies import load_animal
from zoetic.errors import ZoeticError
from zoetic.io import read_toml
from zoetic.perception.eyes import (
    EyeSpec,
    HeadFrame,
    composite,
    eye_cameras,
    eye_positions,
    head_frame,
    look,
)
from zoetic.perception.gaze import (
    GazeController,
    GazeState,
    fixation,
    image_shift,
    saccade,
    vergence_range,
)
from zoetic.perception.recognition import N_BINS, histogram, intersection, locate, recognise
from zoetic.physics.world import placed_pose
from zoetic.render import project
from zoetic.render.scene import Mesh, _sphere, shade

FRAME = HeadFrame(np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0]))
RED, YELLOW = (0.85, 0.12, 0.1), (0.9, 0.85, 0.1)


def _balls(centres, colours, radius=0.1) -> Mesh:
    vs, ts, cs, base = [], [], [], 0
    for c, col in zip(centres, colours, strict=True):
        v, t = _sphere(np.asarray(c, float), radius)
        vs.append(v)
        ts.append(t + base)
        cs.append(np.tile(col, (len(t), 1)))
        base += len(v)
    v, t = np.concatenate(vs), np.concatenate(ts)
    return Mesh(v, t, shade(v, t, np.concatenate(cs)), np.zeros(len(t), np.int64))


def _red_model(spec: EyeSpec) -> np.ndarray:
    img, _ = look(_balls([(1.0, 0, 0)], [RED]), FRAME, np.zeros((2, 2)), spec)
    fov = img[0, -1]
    return histogram(fov, fov[..., 0] > 2 * fov[..., 2])


def test_a_point_projects_to_the_expected_pixel_in_every_level():
    spec = EyeSpec.of(load_animal("shark"))
    cams = eye_cameras(FRAME, np.zeros((2, 2)), spec)
    # a point straight ahead of the left eye projects onto the centre of all its levels
    left = np.array(spec.offset)
    uv, _ = project([left + [2.0, 0.0, 0.0]], cams)
    assert np.allclose(uv[:4, 0], 32.0)
    # 0.1 m to the right at 2 m: 0.05 rad off axis, focal f_l pixels to the right in level l
    uv, _ = project([left + [2.0, 0.0, -0.1]], cams)
    assert np.allclose(uv[:4, 0, 0], 32.0 + spec.focals * 0.05)


def test_the_retina_composites_levels_with_borders():
    lev = np.stack([np.full((64, 64, 3), 40 * (k + 1), np.uint8) for k in range(4)])
    img = composite(lev, 256)
    assert img[5, 5, 0] == 40 and img[128, 128, 0] == 160 and img[64, 100, 0] == 255


def test_the_histogram_model_finds_a_red_square_and_ignores_a_yellow_one():
    img = np.zeros((64, 64, 3), np.uint8)
    img[...] = (20, 70, 90)
    img[40:48, 10:18] = (210, 30, 25)
    img[8:20, 40:52] = (230, 215, 30)
    model = histogram(img[40:48, 10:18])
    det = locate(img, model)
    assert abs(det.col - 14) < 1 and abs(det.row - 44) < 1 and det.strength > 0.9
    assert intersection(histogram(img[40:48, 10:18]), model) > 0.99
    assert intersection(histogram(img[8:20, 40:52]), model) < 0.01


def test_a_saccade_centres_the_target_in_the_fovea_in_one_step():
    spec = EyeSpec.of(load_animal("shark"))
    model = _red_model(spec)
    mesh = _balls([(2.5, 0.3, -1.2), (2.0, -0.2, 1.0)], [RED, YELLOW], radius=0.2)
    img, cams = look(mesh, FRAME, np.zeros((2, 2)), spec)
    det = locate(img[0, 0], model)  # in the periphery, off to the right
    assert det.strength > 0.2 and det.col > 40
    angles = np.zeros((2, 2))
    angles[0] = saccade(FRAME, cams, 0, det.col, det.row)
    img2, _ = look(mesh, FRAME, angles, spec)
    centre = locate(img2[0, 3], model)
    # one peripheral pixel is 8 foveal ones: centred within a peripheral pixel
    assert np.hypot(centre.col - 32, centre.row - 32) < 8
    target = np.array([2.5, 0.3, -1.2]) - np.array(spec.offset)
    assert np.isclose(angles[0, 0], np.arctan2(target[2], target[0]), atol=0.03)


def test_two_eyes_verge_on_the_target_and_triangulate_its_range():
    spec = EyeSpec.of(load_animal("shark"))
    model = _red_model(spec)
    point = np.array([1.5, 0.1, 0.3])
    mesh = _balls([point], [RED], radius=0.06)
    ctl = GazeController(model, spec)
    state = GazeState()
    for _ in range(3):
        img, cams = look(mesh, FRAME, state.angles, spec)
        state = ctl.step(state, FRAME, img, cams)
    assert state.locked.all() and state.angles[1, 0] > state.angles[0, 0]  # theta_V > 0
    x, rng = fixation(FRAME, state.angles, spec)
    true = np.linalg.norm(point - np.array([spec.offset[0], 0, 0]))
    assert abs(rng - true) < 0.1 * true and np.linalg.norm(x - point) < 0.15 * true
    flat = vergence_range(0.0 - np.arctan2(0.06, 1.0), np.arctan2(0.06, 1.0), 0.12)
    assert np.isclose(flat, 1.0, rtol=1e-6)


def test_the_stabiliser_recovers_a_known_image_shift():
    rng = np.random.default_rng(0)
    from scipy.ndimage import gaussian_filter, shift

    base = gaussian_filter(rng.random((80, 80)), 2.0)
    for du, dv in ((1.5, -0.7), (-2.5, 1.0)):
        moved = shift(base, (dv, du), order=3, mode="nearest")
        u, v = image_shift(base[8:-8, 8:-8], moved[8:-8, 8:-8])
        assert abs(u - du) < 0.15 and abs(v - dv) < 0.15


def test_eyes_sit_on_the_head_of_a_placed_fish():
    shark = load_animal("shark")
    pos = placed_pose(shark, (0.0, 0.0, 0.0), yaw=0.5)
    fr = head_frame(shark, pos)
    assert np.allclose(fr.forward, [np.cos(0.5), 0.0, np.sin(0.5)], atol=1e-6)
    assert np.allclose(fr.up, [0, 1, 0], atol=1e-6) and np.allclose(fr.origin, pos[shark.head])


def test_the_animal_file_places_the_eyes_and_sets_their_fields_of_view(tmp_path):
    import tomli_w

    from zoetic.bodies import ZOO_DIR

    doc = read_toml(ZOO_DIR / "shark.toml")
    doc["eyes"] = {
        "node": "r1_1",
        "offset": [0.02, 0.05, 0.1],
        "fov": 80.0,
        "levels": 3,
        "pixels": 24,
    }
    path = tmp_path / "wide-eyed.toml"
    path.write_text(tomli_w.dumps(doc))
    fish = load_animal(path)
    spec = EyeSpec.of(fish)
    pos = placed_pose(fish, (0.0, 0.0, 0.0), yaw=0.5)
    fr = head_frame(fish, pos)
    node = pos[fish.node_names.index("r1_1")]
    assert np.allclose(fr.origin, node)
    left = node + 0.02 * fr.forward + 0.05 * fr.up + 0.1 * fr.left
    right = node + 0.02 * fr.forward + 0.05 * fr.up - 0.1 * fr.left
    assert np.allclose(eye_positions(fr, spec), [left, right])
    cams = eye_cameras(fr, np.zeros((2, 2)), spec)
    assert np.allclose(np.degrees(cams.fov), [80.0, 40.0, 20.0] * 2)
    assert cams.size == (24, 24) and np.allclose(cams.eye[:3], left)
    img, _ = look(_balls([node + 2.0 * fr.forward], [RED]), fr, np.zeros((2, 2)), spec)
    assert img.shape == (2, 3, 24, 24, 3)
    del doc["eyes"]
    blind = tmp_path / "blind.toml"
    blind.write_text(tomli_w.dumps(doc))
    with pytest.raises(ZoeticError, match=r"blind\.toml.*no eyes.*\[eyes\]"):
        EyeSpec.of(load_animal(blind))


def test_correlating_two_foveas_finds_their_disparity():
    from scipy.ndimage import gaussian_filter, shift

    from zoetic.perception.gaze import correlate

    base = gaussian_filter(np.random.default_rng(1).random((64, 64)), 1.5)
    moved = shift(base, (-2.0, 5.0), order=3, mode="wrap")  # content 5 px right, 2 px up
    u, v, peak = correlate(base, moved)
    assert abs(u - 5.0) < 0.3 and abs(v + 2.0) < 0.3 and peak > 0.3


def test_matching_a_point_finds_it_in_the_other_image_to_a_fraction_of_a_pixel():
    from scipy.ndimage import gaussian_filter, shift

    from zoetic.perception.gaze import match

    base = gaussian_filter(np.random.default_rng(1).random((64, 64)), 1.5)
    moved = shift(base, (-2.3, 5.4), order=3, mode="nearest")  # content 5.4 px right, 2.3 up
    col, row, score = match(base, moved, 30.5, 30.5)
    assert col == pytest.approx(35.9, abs=0.15) and row == pytest.approx(28.2, abs=0.15)
    assert score > 0.9
    # searched only near a guess, the same point
    near = match(base, moved, 30.5, 30.5, near=(36.0, 28.0), radius=2)
    assert near[:2] == pytest.approx((col, row))


def test_the_whole_image_correlation_by_fft_scores_every_square_as_one_by_one():
    from scipy.ndimage import gaussian_filter

    from zoetic.perception.gaze import ncc_everywhere
    from zoetic.perception.kernels import ncc_scores

    rng = np.random.default_rng(4)
    img = gaussian_filter(rng.random((64, 64)), 1.0)
    img[:, :20] = 0.0  # no target there: all-zero squares
    img[40:, 30:] = 0.3  # a flat patch
    pb = np.pad(img, 8)
    tpl = pb[30:47, 25:42] - pb[30:47, 25:42].mean()
    tn = float(np.sqrt((tpl * tpl).sum()))
    one = np.empty((64, 64))
    ncc_scores(tpl, tn, pb, 0, 64, 0, 64, one)
    every = ncc_everywhere(tpl, tn, pb)
    assert (one == -1.0).sum() > 300  # the flat squares are there
    assert np.array_equal(every == -1.0, one == -1.0)
    assert np.abs(every - one).max() < 1e-9
    assert np.unravel_index(np.argmax(every), every.shape) == (30, 25)  # the template's own


def _prey_range_error(dist: float, yaw: float, bearing: float, frames: int = 6) -> float:
    """Return the relative error of the range two eyes at FRAME triangulate to a prey shark
    whose centre of mass lies ``dist`` m from them at ``bearing`` rad, turned ``yaw`` rad,
    after ``frames`` frames of a still scene, against where the left gaze meets its skin."""
    from zoetic.perception.pursuit import FOG, PREY, gazed_range, learn_model
    from zoetic.render import world_mesh

    shark = load_animal("shark")
    spec = EyeSpec.of(shark)
    eyes = eye_positions(FRAME, spec)
    com = (shark.mass @ shark.rest_pos) / shark.total_mass
    centre = eyes.mean(0) + dist * np.array([np.cos(bearing), 0.0, np.sin(bearing)])
    pos = placed_pose(shark, centre - com, yaw)
    model = learn_model(shark, placed_pose(shark, eyes.mean(0) + (2.0, 0, 0) - com), PREY, spec)
    mesh = world_mesh([shark], [pos], [PREY])
    ctl, state = GazeController(model, spec), GazeState()
    for _ in range(frames):
        img, cams = look(mesh, FRAME, state.angles, spec, FOG)
        state = ctl.step(state, FRAME, img, cams)
    assert state.locked.all()
    _, rng = fixation(FRAME, state.angles, spec)
    true = gazed_range(shark.faces, pos, eyes, state.directions[0])
    return abs(rng - true) / true


@pytest.mark.parametrize("yaw, bearing", [(0.0, 0.15), (0.5, -0.2), (-2.4, 0.15)])
def test_vergence_ranges_a_prey_a_metre_away_within_ten_percent(yaw, bearing):
    # a 1 m fish a metre away fills more than the fovea; the eyes must fixate one spot of it
    assert _prey_range_error(1.0, yaw, bearing) < 0.10


@pytest.mark.slow
@pytest.mark.parametrize("dist", [0.6, 1.0, 2.0, 3.0])
def test_the_median_range_error_over_views_is_under_ten_percent(dist):
    views = [(y, b) for y in (0.0, 0.5, 1.2, 2.0, 2.8, -0.7, -1.5, -2.4) for b in (-0.2, 0.15)]
    assert np.median([_prey_range_error(dist, y, b) for y, b in views]) < 0.10


def test_the_vestibulo_ocular_reflex_keeps_the_gaze_on_the_target_as_the_head_turns():
    spec = EyeSpec.of(load_animal("shark"))
    model = _red_model(spec)
    mesh = _balls([(2.0, 0.1, 0.4)], [RED], radius=0.1)
    ctl = GazeController(model, spec)
    state = GazeState()
    for _ in range(3):
        img, cams = look(mesh, FRAME, state.angles, spec)
        state = ctl.step(state, FRAME, img, cams)
    # the head yaws 12 deg (more than the fovea's half field of 7.5 deg) between frames
    c, s = np.cos(np.radians(12.0)), np.sin(np.radians(12.0))
    turned = HeadFrame(
        np.zeros(3), np.array([c, 0, s]), np.array([0, 1.0, 0]), np.array([-s, 0, c])
    )
    held = ctl.hold(state, turned)
    assert np.allclose(held.angles[:, 0], state.angles[:, 0] - np.radians(12.0), atol=1e-6)
    img, _ = look(mesh, turned, held.angles, spec)
    assert locate(img[0, -1], model).strength > 0.5  # still in the fovea
    img, _ = look(mesh, turned, state.angles, spec)  # without the reflex it has left it
    assert locate(img[0, -1], model).strength < 0.2


def test_recognise_refuses_images_that_are_not_uint8():
    models = np.full((1, N_BINS), 1.0 / N_BINS)
    for dtype in (np.float64, np.int64):
        with pytest.raises(ValueError, match=np.dtype(dtype).name):
            recognise(np.full((1, 16, 16, 3), 300, dtype), models)
    img = np.zeros((1, 16, 16, 3), np.uint8)
    img[0, 4:8, 4:8] = (200, 30, 30)
    got = recognise(img, models)
    assert np.array_equal(got.histograms[0], histogram(img[0]))
